// The hand's pose in one frame: the landmark model's metric 3D landmarks
// (a hand-centred frame) placed in the camera frame so that they project
// onto its 2D keypoints (OpenCV's SQPnP, the global minimum of the
// reprojection error; confidences below 0.05 leave a keypoint out).
#pragma once

#include <array>
#include <optional>

#include "core/geometry.h"
#include "hands/hand_observation.h"

namespace doasido::hands {

struct HandPose {
  Mat3 R = Mat3::Identity();  // model frame -> camera frame
  Vec3 t = Vec3::Zero();
  // The 21 landmarks in the camera frame, metres.
  std::array<Vec3, kJoints> joints;
};

// nullopt when fewer than 6 keypoints are usable or the solution puts the
// hand behind the camera.
std::optional<HandPose> SolveHandPose(const HandObservation& hand, const Mat3& K);

}  // namespace doasido::hands
