// One object as the Objectron box-landmark models saw it in one frame: the
// plain record the objects domain hands on (to the 3D lifting, the JSON
// writer and the overlay). Only 2D: pixels of the input frame as displayed
// (after its display rotation), origin at the top-left pixel's corner.
#pragma once

#include <array>
#include <string>

#include <Eigen/Core>

namespace doasido::objects {

// Keypoint 0 is the box centre; 1-8 the corners, in the order of MediaPipe's
// python/solutions/objectron.py (BoxLandmark): 1 back-bottom-left,
// 2 front-bottom-left, 3 back-top-left, 4 front-top-left, 5 back-bottom-right,
// 6 front-bottom-right, 7 back-top-right, 8 front-top-right. So for corner k
// (1-8), k-1 in binary is (right, top, front): +x, +y, +z of the box.
inline constexpr int kBoxKeypoints = 9;

struct ObjectObservation {
  int frame = 0;         // index of the frame in the input (0-based, decode order)
  std::string category;  // "cup" | "sneakers" | "chair" | "camera" (the model that ran)
  float score = 0;       // the box-landmark model's presence, 0..1
  int track = 0;         // one id per tracked object in the input; its category never changes
  std::array<Eigen::Vector2d, kBoxKeypoints> keypoints_2d;  // pixels, 0 = centre, 1-8 corners
};

}  // namespace doasido::objects
