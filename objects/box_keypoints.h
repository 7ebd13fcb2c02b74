// One object's box keypoints in one frame, as the Objectron box-landmark
// models give them (REFERENCE.md §10; google/mediapipe
// modules/objectron/calculators/box.cc and python/solutions/objectron.py):
// keypoint 0 is the box centre, 1-8 its corners. In the box's own frame
// (x to the right face, y to the top face, z to the front face, each
// half-extent 1) corner i has the signs of BoxCorner(i): x from bit 2 of
// i-1, y from bit 1, z from bit 0 (1 = (-,-,-), 2 = (-,-,+), ...,
// 8 = (+,+,+)).
#pragma once

#include <array>
#include <string>

#include <Eigen/Core>

namespace doasido::objects {

inline constexpr int kBoxKeypoints = 9;

struct ObjectObservation {
  int frame = 0;          // frame of the clip's span (0 = its first frame), as the bundle's
  std::string category;   // kCategory* of objects/object_categories.h
  float score = 0;        // the box-landmark model's presence
  int track = 0;          // one id per object for the clip; its category fixed
  // Pixels of the frame as displayed (rotation applied), pixel centres at
  // integers: 0 the centre, 1-8 the corners in the order above.
  std::array<Eigen::Vector2d, kBoxKeypoints> keypoints_2d;
};

// Corner i (0 = the centre) of the box with half-extents 1, in its own frame.
inline Eigen::Vector3d BoxCorner(int i) {
  if (i == 0) return Eigen::Vector3d::Zero();
  const int b = i - 1;
  return {(b & 4) ? 1.0 : -1.0, (b & 2) ? 1.0 : -1.0, (b & 1) ? 1.0 : -1.0};
}

}  // namespace doasido::objects
