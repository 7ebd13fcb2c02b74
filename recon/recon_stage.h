// The `recon` queue stage: a clip bundle becomes the metric, gravity-aligned
// hand-object trajectory of recon/reconstruction.h (seed §3.1).
//
// Input: the clip bundle (recon/bundle/bundle_location.h BundleDir). Object poses:
// when <artifacts>/<clip>/track/object_poses.npz exists (written by the
// `track` stage, recon/track_stage.h) its `poses` (T,7) f8, object->camera,
// t xyz + quaternion wxyz, point-map units, NaN rows = no pose; else the
// bundle's object/poses.npz.
// Steps: hand-object alignment (hand_object_alignment.h) rescales each
// frame's object translation to the hand's metric scale; gravity
// (gravity.h) rotates camera coordinates so up is +z; the floor z = 0 is
// put under the object's resting pose (the lowest point of the posed mesh in
// the first frame where the object moves less than rest_speed, else in the
// slowest frame). The right hand's joints are taken as metric (HaWoR).
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
#include "db/stage.h"
#include "recon/bundle/bundle.h"
#include "recon/bundle/bundle_location.h"
#include "recon/align/gravity.h"
#include "recon/align/hand_object_alignment.h"
#include "recon/reconstruction.h"
#include "recon/track_stage.h"

namespace doasido::recon {

inline constexpr const char* kReconStageName = "recon";

// Reason codes.
inline constexpr const char* kReasonNoObject = "no_object";
inline constexpr const char* kReasonNoHands = "no_hands";  // hand-only bundle, no valid frame
inline constexpr const char* kReasonTooFewAlignedFrames = "too_few_aligned_frames";
inline constexpr const char* kReasonScaleInconsistent = "scale_inconsistent";

// Measurement keys.
inline constexpr const char* kMeasureFrames = "frames";
inline constexpr const char* kMeasurePosedFrames = "posed_frames";
inline constexpr const char* kMeasureAlignedFrames = "aligned_frames";
inline constexpr const char* kMeasureEvidenceShare = "evidence_share";  // aligned / posed
inline constexpr const char* kMeasureScaleMedian = "scale_median";
inline constexpr const char* kMeasureScaleSpread = "scale_spread";  // 1.4826 MAD of log s
inline constexpr const char* kMeasureHandObjectDistance = "hand_object_distance_m";  // per frame
inline constexpr const char* kMeasureHandObjectDistanceMedian = "hand_object_distance_median_m";
inline constexpr const char* kMeasurePoseJitter = "pose_jitter_m";  // median |acceleration| per frame
inline constexpr const char* kMeasureGravitySource = "gravity_source";
inline constexpr const char* kMeasureGravityInlierShare = "gravity_inlier_share";
inline constexpr const char* kMeasurePoseSource = "object_pose_source";  // "track" or "bundle"
// Hand-only reconstructions (no object part in the bundle).
inline constexpr const char* kMeasureObject = "object";              // kObjectNone when hand-only
inline constexpr const char* kObjectNone = "none";
inline constexpr const char* kMeasureGravityAssumed = "gravity_assumed";  // camera-up taken as up
inline constexpr const char* kMeasureIntrinsicsAssumed = "intrinsics_assumed";  // the hands stage's
inline constexpr const char* kMeasureRightFrames = "right_frames";    // frames the hand is seen
inline constexpr const char* kMeasureLeftFrames = "left_frames";
inline constexpr const char* kMeasureWristJumpMax = "wrist_jump_max_m";  // largest frame-to-frame step
inline constexpr const char* kMeasureBundleSource = "bundle_source";  // bundle_location.h kBundleFrom*
// How far below the hands' lowest joint a hand-only clip's floor lies, m
// (recon and retarget_kinematic's bundle fallback agree on it).
inline constexpr double kHandOnlyFloorMargin = 0.05;


struct ReconStageConfig {
  HandObjectAlignmentConfig alignment;
  GravityConfig gravity;
  double min_aligned_fraction = 0.3;
  int min_aligned_frames = 5;
  double max_scale_spread = 0.25;
  double rest_speed = 0.002;  // m per frame
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ReconStageConfig, alignment, gravity,
                                                min_aligned_fraction, min_aligned_frames,
                                                max_scale_spread, rest_speed)
void CheckConfig(const ReconStageConfig& c, const std::string& section);

struct ReconOutput {
  Reconstruction reconstruction;  // object_mesh left empty (the caller writes the mesh)
  HandObjectAlignment alignment;
  GravityEstimate gravity;
  Mat3 camera_to_world = Mat3::Identity();  // rotation; then z -= floor offset
  double floor_offset = 0;
  Json measurements = Json::object();
};

// Aligns and gravity-aligns one bundle. `poses` (T) object->camera in point
// map units with `pose_valid`. Requires bundle.object_mesh.
ReconOutput Reconstruct(const ClipBundle& bundle, const std::vector<Pose>& poses,
                        const std::vector<bool>& pose_valid, const ReconStageConfig& config);

// A bundle with a hand and no object part at all (mesh, poses, candidates,
// masks): the hands stage's bundle, or a model command's without an object.
bool IsHandOnly(const ClipBundle& bundle);

// The hands alone: gravity from the bundle (gravity.npz, else the support
// plane of a point map), else camera-up recorded as assumed; the floor
// z = 0 kHandOnlyFloorMargin below the lowest joint of either hand; no
// object (object_valid all false, no mesh). Measurements kMeasureObject,
// kMeasureGravity*, kMeasureRight/LeftFrames, kMeasureWristJumpMax.
ReconOutput ReconstructHandOnly(const ClipBundle& bundle, const ReconStageConfig& config);

// Reads a tracker's object_poses.npz (format in the file comment). Throws
// Error("bad_track") naming the file and field.
void ReadTrackPoses(const std::filesystem::path& file, int frames, std::vector<Pose>& poses,
                    std::vector<bool>& valid);

class ReconStage : public Stage {
 public:
  explicit ReconStage(ReconStageConfig config = {});
  std::string Name() const override { return kReconStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;
  std::optional<StageResult> Redecide(const Json& measurements) const override;

 private:
  StageResult RunHandOnly(const ClipContext& context, const ResolvedBundle& resolved) const;
  ReconStageConfig config_;
};

}  // namespace doasido::recon
