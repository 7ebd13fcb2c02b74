// The whole of the hands stage after detection: tracks (hands/hand_tracker.h),
// then one skeleton fit per track (hands/hand_skeleton_fit.h), with the
// numbers the stage records about them.
#pragma once

#include <string>
#include <vector>

#include "core/config.h"
#include "hands/hand_detection.h"
#include "hands/hand_intrinsics.h"
#include "hands/hand_skeleton_fit.h"
#include "hands/hands_config.h"

namespace doasido::hands {

struct HandsResult {
  Intrinsics intrinsics;
  std::vector<FittedTrack> tracks;  // by first frame; tracks without any pose are left out
  TrackingSummary tracking;
  double fit_seconds = 0;
  // The size the fit assumed (FitConfig): "adult" (the template under a
  // prior on its length, recorded as assumed) or "model".
  std::string size_prior;
  double prior_hand_length_m = 0;  // the prior's centre, "adult" only
};

// `fps` <= 0 (an image) is taken as 30 (the acceleration term needs a rate;
// a one-frame track has none). Tracks shorter than the tracker's minimum
// are kept when the input itself is that short (an image: one frame).
HandsResult ReconstructHands(const DetectedFrames& detected, const Intrinsics& intrinsics,
                             const HandsConfig& config);

// Measurements of a result: frames, per side the frames with a valid hand,
// filled frames, tracks, palm width (median over frames, metres) and hand
// length (median over tracks' frames, metres), the size prior, PnP poses
// dropped as flips or as mirrored 3D hands, frames untrusted
// (hands/hand_outliers.h), the
// largest frame-to-frame wrist move per side as hands.npz holds it (across
// tracks too; metres), the mean reprojection error
// (pixels), seconds.
Json Summarize(const DetectedFrames& detected, const HandsResult& result);

}  // namespace doasido::hands
