// One hand as the models saw it in one frame, in the terms the tracker and
// the fit use: pixels of the input as displayed, the probability that it is
// a right hand, and the model's own metric 3D landmarks.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "filters/hand_landmarker.h"

namespace doasido::hands {

inline constexpr int kJoints = kHandKeypoints;
// The parent of each joint in the hand's tree (wrist = -1): the 20 bones.
inline constexpr int kParent[kJoints] = {-1, 0, 1, 2, 3, 0, 5, 6, 7, 0, 9,
                                         10, 11, 0, 13, 14, 15, 0, 17, 18, 19};

enum class Side { kLeft = 0, kRight = 1 };
const char* SideName(Side side);  // "left" | "right"

struct HandObservation {
  double score = 0;    // the landmark model's hand presence, 0..1
  double p_right = 0;  // probability of a right hand as the camera sees it (not mirrored)
  std::array<Eigen::Vector2d, kJoints> uv;          // pixels
  std::array<double, kJoints> confidence{};         // 0..1 per keypoint
  std::array<Eigen::Vector3d, kJoints> world;       // metres, the model's hand-centred frame
};

// The hands of one frame.
using FrameObservations = std::vector<HandObservation>;

// A landmarker hand in a frame of `width` x `height` pixels, scaled by
// `scale` (keypoints found on a shrunk frame times `scale` are in the
// input's pixels). The models give no per-keypoint confidence, so a
// keypoint's is the hand's presence, lowered for keypoints the model had to
// place outside the frame (there it extrapolates): linearly to 0 at a tenth
// of the frame's longer side beyond the border.
HandObservation FromLandmarked(const filters::LandmarkedHand& hand, double scale, int width,
                               int height);

// Palm width: the distance between the index and little fingers' bases
// (joints 5 and 17), the measure the real-clip check compares with adult
// hands (7-10 cm).
double PalmWidth(const std::array<Eigen::Vector3d, kJoints>& joints);

}  // namespace doasido::hands
