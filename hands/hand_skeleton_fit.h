// One Ceres problem per track: the hand's 21 joints in the camera frame on
// every frame of the track, with bone lengths constant over the clip.
//
// Unknowns: each joint's position per frame (metres, camera frame). The
// skeleton's link lengths are the track's constants, the models' median
// lengths over its frames: the 20 bones, and the link across the palm
// between the index and little fingers' bases (5-17), which holds the
// palm's width (the metacarpal heads barely move against each other;
// without it a palm seen edge-on or filled across a gap folded to 2 cm; a
// long link, because a median length of noisy landmarks is too long by
// about sigma^2 / length, which would bias short links most). They are the only
// metric cue: left free, every residual below prefers a smaller, nearer
// hand (same projection, less motion), and the fitted hands of real clips
// shrank to half size. Residuals, each divided by its sigma (FitConfig):
//   - reprojection of every observed keypoint against the models' 2D
//     keypoint, times sqrt(confidence), under a Huber loss (a keypoint the
//     models misplace is outvoted, not obeyed); the sigma is a fraction of
//     the hand's size in the image, so it means the same at any resolution;
//   - each link's length against the track's constant length;
//   - on observed frames, the wrist-relative joints against the model's 3D
//     landmarks turned into the camera by the frame's PnP pose (the depth
//     of the fingers that one view does not show);
//   - every joint's acceleration (x[t+1] - 2 x[t] + x[t-1]) * fps^2.
// Initial values: the PnP pose of each observed frame (hands/hand_pnp.h),
// gaps linearly interpolated between their neighbours. Frames of a gap have
// no reprojection or shape residual: the bones and the acceleration carry
// them across, and they are marked filled.
#pragma once

#include <array>
#include <optional>
#include <utility>
#include <vector>

#include "core/geometry.h"
#include "hands/hand_tracker.h"

namespace doasido::hands {

using Joints = std::array<Vec3, kJoints>;

struct FittedTrack {
  Side side = Side::kRight;
  int first_frame = 0;
  std::vector<Joints> joints;     // per frame of the track, camera frame, metres
  std::vector<bool> filled;       // the frame had no observation (or no PnP pose)
  std::vector<std::optional<HandObservation>> observations;  // the track's, per frame
  std::vector<bool> has_pnp;      // the frame's PnP pose exists (before the fit)
  std::vector<Joints> pnp_joints;  // those poses' joints (zero where !has_pnp)
  std::vector<double> link_length;  // metres, in SkeletonLinks() order
  double reprojection_rms_px = 0;  // observed keypoints, after the fit
  double seconds = 0;              // the solve
  int iterations = 0;
  int last_frame() const { return first_frame + static_cast<int>(joints.size()) - 1; }
};

// The links held at constant length: (child, parent) of the 20 bones, then
// (17, 5) across the palm.
std::vector<std::pair<int, int>> SkeletonLinks();

// Fits `track` seen through `K` at `fps` frames per second. A track on which
// no frame has a PnP pose returns with empty `joints`.
FittedTrack FitTrack(const Track& track, const Mat3& K, double fps, const FitConfig& config);

}  // namespace doasido::hands
