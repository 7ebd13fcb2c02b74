// The `recon` queue stage: a clip bundle becomes the metric, gravity-aligned
// hand-object trajectory of recon/reconstruction.h (seed §3.1).
//
// Input: the clip bundle (stages/clip_inputs.h BundleDir). Object poses:
// when <artifacts>/<clip>/track/object_poses.npz exists (written by the
// `track` stage, stages/track_stage.h) its `poses` (T,7) f8, object->camera,
// t xyz + quaternion wxyz, point-map units, NaN rows = no pose; else the
// bundle's object/poses.npz.
// Steps: hand-object alignment (hand_object_alignment.h) rescales each
// frame's object translation to the hand's metric scale; gravity
// (gravity.h) rotates camera coordinates so up is +z; the floor z = 0 is
// put under the object's resting pose (the lowest point of the posed mesh in
// the first frame where the object moves less than rest_speed, else in the
// slowest frame), or lower where the object gets lower on another frame (a
// held object that pauses before it is set down: reconstruction.json
// floor.lowest_frame). The right hand's joints are taken as metric (HaWoR).
// Output in artifact_dir: reconstruction.npz, object.obj, reconstruction.json
// (gravity source and inlier share, per-frame scales and how each frame was
// filled, skipped frames with reasons, object pose source).
// A hand-only bundle (IsHandOnly: hands, no object part) is reconstructed
// without object (ReconstructHandOnly; no object.obj), passed, or rejected
// kReasonNoHands when no frame holds a hand.
// Measurements (keys below) and verdict: reject kReasonNoObject (an object
// part without mesh, poses or object mask, or neither object nor hands), kReasonTooFewAlignedFrames (aligned share of
// the frames with a pose below min_aligned_fraction, or fewer than
// min_aligned_frames); flag kReasonScaleInconsistent when the robust spread
// of log s over aligned frames exceeds max_scale_spread.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "recon/align/reconstruct.h"
#include "stages/clip_inputs.h"
#include "stages/shared_reasons.h"
#include "stages/stage.h"
#include "stages/track_stage.h"

namespace doasido::recon {

// Valid ranges of the recon stage's configuration; throws Error("bad_config").
void CheckConfig(const ReconStageConfig& c, const std::string& section);

}  // namespace doasido::recon

namespace doasido::stages {

// The stage's name kReconStageName is recon/reconstruction.h's (the
// artifact folder its readers find).

// Reason codes (and kReasonNoObject, kReasonNoHands: a hand-only bundle
// with no valid frame; stages/shared_reasons.h).
inline constexpr const char* kReasonTooFewAlignedFrames = "too_few_aligned_frames";
inline constexpr const char* kReasonScaleInconsistent = "scale_inconsistent";

// The stage's configuration is recon::ReconStageConfig
// (recon/align/reconstruct.h), its measurement keys kMeasure* there too; its
// check is in namespace recon (above), beside the type, where
// ReadCheckedSection finds it.

// Reads a tracker's object_poses.npz (format in the file comment). Throws
// Error("bad_track") naming the file and field.
void ReadTrackPoses(const std::filesystem::path& file, int frames, std::vector<Pose>& poses,
                    std::vector<bool>& valid);

class ReconStage : public Stage {
 public:
  explicit ReconStage(recon::ReconStageConfig config = {});
  std::string Name() const override { return recon::kReconStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;
  std::optional<StageResult> Redecide(const Json& measurements) const override;

 private:
  StageResult RunHandOnly(const ClipContext& context, const ResolvedBundle& resolved) const;
  recon::ReconStageConfig config_;
};

}  // namespace doasido::stages
