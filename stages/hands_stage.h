// The `hands` queue stage: after the filters, before `bundle`. On every
// frame of the clip's kept span it runs the MediaPipe hand models (the same
// detector seam as the filters: filters/hand_landmarker.h), links the hands
// into tracks with one side each (hands/hand_tracker.h), places them in the
// camera frame in metres (per-frame PnP, then one Ceres skeleton fit per
// track: hands/hand_skeleton_fit.h), and writes the hand part of a clip
// bundle into its artifact folder <artifacts>/<clip>/hands/
// (hands/hand_bundle_writer.h: meta.json, K.npz, hands.npz, keypoints.json).
//
// The kept span: the shot-boundary stage's trim when it trimmed the clip,
// else the clip's span from its list (start/end frame or seconds), else the
// whole video. meta.json's frames is that span's frame count; the stage's
// measurements record its first and last file frame.
//
// Intrinsics (hands/hand_intrinsics.h): the K of a bundle the list names,
// else the list's fx/fy/cx/cy or fov columns, else `default_fov_deg`,
// recorded as assumed (meta.json "intrinsics_assumed").
//
// A clip whose list names a bundle that has hands (hands.npz) is passed at
// once, measurement "skipped": that bundle wins (the `bundle` stage uses
// this stage's hands only where the bundle has none).
//
// Verdicts: pass; reject `no_hands` when no track survives (the bundle is
// still written, every frame invalid). Errors (clip named): the decoder's
// (video_open_failed, video_truncated: permanent), bad_intrinsics
// (permanent), hand_detector_unavailable / hand_detector_failed (retried:
// a missing runtime can be installed, a crashed process restarted).
#pragma once

#include <memory>

#include "filters/hand_landmarker.h"
#include "hands/hand_intrinsics.h"
#include "hands/hands_config.h"
#include "stages/shared_reasons.h"
#include "stages/stage.h"

namespace doasido::stages {

// Reason code: reject kReasonNoHands (stages/shared_reasons.h).

class HandsStage : public Stage {
 public:
  explicit HandsStage(hands::HandsConfig config = {});
  ~HandsStage() override;
  std::string Name() const override { return hands::kHandsStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;
  // Builds the hand models' graphs (native runtime) before the first clip.
  void Prepare() override;

 private:
  hands::HandsConfig config_;
  // Started on the first clip and kept for the next ones (Node and the
  // models take about a second to load).
  std::unique_ptr<filters::HandLandmarker> landmarker_;
};

// The intrinsics for `context`'s clip at `width` x `height` (see above).
hands::Intrinsics ClipIntrinsics(const ClipContext& context, int width, int height,
                          double default_fov_deg);

}  // namespace doasido::stages
