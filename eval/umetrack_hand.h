// The UmeTrack hand model (HOT3D's `umetrack_hand_user_profile.json` and
// `umetrack_hand_pose_trajectory.jsonl`): a personalised skeleton of 22
// one-axis joints (4 per finger, thumb first, then 2 at the wrist that the
// landmarks do not use) and 21 skinned landmarks, and its forward kinematics.
//
// Facts of the format (HOT3D's hand_tracking_toolkit, emg2pose):
//  - lengths of the model are millimetres; the wrist transform of a pose is
//    hand -> world in metres (its quaternion stored w, x, y, z);
//  - the model is a left hand; a right hand is its mirror image: the wrist
//    transform's x axis is negated before skinning;
//  - joint j rotates by angle_j about axis_j through its rest position:
//    L_j = [R(axis_j, angle_j) | rest_j - R rest_j];
//  - 17 skinning frames: 0 and 1 are the wrist transform W; finger f's
//    frames 2 + 3f .. 4 + 3f are W L_4f L_4f+1, then times L_4f+2, then
//    times L_4f+3;
//  - landmark i = sum_k weight_ik * frame[bone_ik] * rest_landmark_i;
//    landmarks are tips 0-4 (thumb..pinky), wrist 5, thumb intermediate and
//    distal 6-7, then proximal/intermediate/distal of index 8-10, middle
//    11-13, ring 14-16, pinky 17-19, palm centre 20.
#pragma once

#include <array>
#include <filesystem>
#include <vector>

#include "core/geometry.h"
#include "recon/bundle/bundle.h"

namespace doasido::recon {

inline constexpr int kUmeTrackJoints = 22;
inline constexpr int kUmeTrackLandmarks = 21;

struct UmeTrackHand {
  std::array<Vec3, kUmeTrackJoints> axes;   // unit
  std::array<Vec3, kUmeTrackJoints> rest;   // mm, hand frame
  std::array<Vec3, kUmeTrackLandmarks> landmark_rest;          // mm, hand frame
  std::array<std::array<int, 3>, kUmeTrackLandmarks> landmark_bones;
  std::array<std::array<double, 3>, kUmeTrackLandmarks> landmark_weights;
  double scale = 1;  // hand_scale, multiplies the model's lengths
};

// Reads the "hand_model" of a user profile. Throws Error("bad_hand_model")
// naming the file and the field when a member is missing, has the wrong
// shape, is not finite, or a bone index is outside the 17 frames.
UmeTrackHand ReadUmeTrackHand(const std::filesystem::path& profile_json);

enum class HandSide { kLeft, kRight };

// The 21 UmeTrack landmarks (metres, world frame) of `angles` (22 joint
// angles, rad) of the `side` hand at `wrist` (hand -> world, metres).
std::array<Vec3, kUmeTrackLandmarks> UmeTrackLandmarks(const UmeTrackHand& hand,
                                                      const std::array<double, kUmeTrackJoints>& angles,
                                                      const Pose& wrist, HandSide side);

// The same pose as OpenPose-21 joints (wrist; thumb, index, middle, ring,
// pinky, each base to tip). OpenPose's thumb base (CMC), which UmeTrack has
// no landmark for, is the rotation centre of the thumb's second joint.
Joints21 UmeTrackOpenPose21(const UmeTrackHand& hand,
                            const std::array<double, kUmeTrackJoints>& angles, const Pose& wrist,
                            HandSide side);

}  // namespace doasido::recon
