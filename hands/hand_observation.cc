#include "hands/hand_observation.h"

#include <algorithm>
#include <cmath>

namespace doasido::hands {

const char* SideName(Side side) { return side == Side::kRight ? "right" : "left"; }

HandObservation FromLandmarked(const filters::LandmarkedHand& hand, double scale, int width,
                               int height) {
  HandObservation o;
  o.score = hand.score;
  // filters/hand_landmarker.h says the model's `right` is for a mirrored
  // image, but on camera footage it names the hand as it is: the right
  // hands of retarget/human_hand_video.mp4 (dex-retargeting's, palm to the
  // camera) and of videos/02_cups.mp4 (a person facing the camera, the hand
  // at the image's left) both score right > 0.5 (docs/hands.md).
  o.p_right = hand.right;
  const double reach = 0.1 * std::max(width, height);
  for (int j = 0; j < kJoints; ++j) {
    o.uv[j] = Eigen::Vector2d(hand.keypoints[j].x, hand.keypoints[j].y) * scale;
    o.world[j] = Eigen::Vector3d(hand.world[j].x, hand.world[j].y, hand.world[j].z);
    const double outside = std::max({0.0, -o.uv[j].x(), o.uv[j].x() - (width - 1), -o.uv[j].y(),
                                      o.uv[j].y() - (height - 1)});
    o.confidence[j] = hand.score * std::clamp(1.0 - outside / reach, 0.0, 1.0);
  }
  return o;
}

double PalmWidth(const std::array<Eigen::Vector3d, kJoints>& joints) {
  return (joints[5] - joints[17]).norm();
}

}  // namespace doasido::hands
