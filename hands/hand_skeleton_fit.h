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
// Size (FitConfig::size_prior). With "model" the link lengths are the
// landmark model's medians as above. With "adult" (the default) they are
// an adult template hand's, times one scale per track (a Ceres unknown
// under a log-normal prior on the hand's length, wrist to middle fingertip
// along the bones): on the bundled real clips the model's metric hands are
// 0.5-0.95 of an adult's and their palms narrower still (3-5 cm between
// the index and little fingers' bases), and a hand's size is what fixes
// its depth. The model's 3D landmarks then give the shape residual its
// directions at the template's size (scaled by the ratio of the template's
// bone lengths to the model's, summed over the 20 bones). The template is
// the right hand of HOT3D's participant P0003
// (`hot3d_sample/.../umetrack_hand_user_profile.json`, a motion-capture
// hand model; OpenPose-21 joints through eval/umetrack_hand.h at rest):
// 189.55 mm long, 61.6 mm between the index and little fingers' bases (its
// mesh is 82.6 mm wide there, skin to skin), scaled to the prior's length.
// Initial values: the PnP pose of each observed frame (hands/hand_pnp.h),
// gaps linearly interpolated between their neighbours. Frames of a gap have
// no reprojection or shape residual: the bones and the acceleration carry
// them across, and they are marked filled. A PnP pose that turns more than
// `max_pnp_turn_deg` from most poses within 5 frames is a flip (a nearly
// flat hand's mirror pose) and is dropped, and so is the pose of a frame
// whose 3D landmarks are the mirror image of the track's hand
// (hands/hand_outliers.h): that frame keeps its reprojection, loses its
// shape residual and starts interpolated.
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
  std::vector<Joints> joints;   // per frame of the track, camera frame, metres
  std::vector<bool> filled;     // the frame had no observation (or its observation was untrusted)
  std::vector<bool> untrusted;  // the observation was dropped (hands/hand_outliers.h): filled too
  // The track's, per frame (untrusted frames' dropped).
  std::vector<std::optional<HandObservation>> observations;
  int untrusted_frames = 0;   // frames untrusted: filled inside the track, cut off at its ends
  std::vector<bool> has_pnp;  // the frame's PnP pose exists and was kept (before the fit)
  int mirrored_poses = 0;     // PnP poses dropped: the 3D landmarks were mirrored (hand_outliers.h)
  int flipped_poses = 0;      // PnP poses dropped as flips (FitConfig::max_pnp_turn_deg)
  std::vector<Joints> pnp_joints;   // PnP's joints, flips too (zero where PnP found none)
  std::vector<double> link_length;  // metres, in SkeletonLinks() order, after the fit
  bool size_prior = false;          // the adult template and prior set the size
  double scale = 1;                 // the template's scale after the fit (1 without the prior)
  double model_hand_length_m = 0;   // the landmark model's own hand length (medians)
  double reprojection_rms_px = 0;   // observed keypoints, after the fit
  double seconds = 0;               // the solve
  int iterations = 0;
  int last_frame() const { return first_frame + static_cast<int>(joints.size()) - 1; }
};

// The links held at constant length: (child, parent) of the 20 bones, then
// (17, 5) across the palm.
std::vector<std::pair<int, int>> SkeletonLinks();

// The adult template's link lengths (metres, SkeletonLinks() order) scaled
// to a hand `hand_length_m` long; the template's own length and the
// hand length of a set of link lengths (wrist - middle base - tip).
inline constexpr double kTemplateHandLengthM = 0.18955;
std::vector<double> TemplateLinkLengths(double hand_length_m);
double HandLength(const std::vector<double>& link_length);

// Fits `track` seen through `K` at `fps` frames per second, then, where
// the fitted wrist shows untrusted frames (hands/hand_outliers.h, bounds
// in FitConfig), again without their observations. A track on which no frame has
// a PnP pose returns with empty `joints`.
FittedTrack FitTrack(const Track& track, const Mat3& K, double fps, const FitConfig& config);

}  // namespace doasido::hands
