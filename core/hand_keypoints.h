// The order of the 21 hand keypoints that MediaPipe's hand landmarker and
// OpenPose-21 share (and so every hand in a bundle, a reconstruction and a
// HOT3D recording read here): the indices any module reads a hand by.
#pragma once

namespace doasido {

inline constexpr int kHandKeypoints = 21;
inline constexpr int kFingertips[5] = {4, 8, 12, 16, 20};  // thumb .. little finger
// Keypoints the hand's frame and its pointing are read from.
inline constexpr int kWrist = 0, kIndexBase = 5, kMiddleBase = 9, kLittleBase = 17;

}  // namespace doasido
