// From one frame's nine box keypoints to the box in the camera frame, up to
// one scale (REFERENCE.md §10; google/mediapipe
// modules/objectron/calculators/epnp.cc has the control points): EPnP with
// four control points, the box centre c0 and the right-, top- and front-face
// centres c1, c2, c3, so that keypoint i is c0 + sx (c1 - c0) + sy (c2 - c0)
// + sz (c3 - c0) with (sx, sy, sz) = BoxCorner(i). Each keypoint gives two
// rows of M (12 unknowns: the control points in the camera frame); the
// smallest eigenvector of MᵀM is the box up to scale, an affine one (the
// three half-axes need not be square to each other). Its nearest rotation,
// half-axis lengths and centre start a Ceres refinement of a true box
// (rotation, centre, three extents) against the keypoints. One camera sees a
// box twice as large twice as far alike: the result is normalised to
// extents whose geometric mean is 1, the centre in the same unit. OpenCV
// camera axes (x right, y down, z forward), pixels of the frame as displayed.
#pragma once

#include <array>

#include "core/geometry.h"
#include "objects/box_keypoints.h"

namespace doasido::objects {

using BoxKeypoints = std::array<Vec2, kBoxKeypoints>;

// Corner i (0 = the centre) of the box with half-extents 1, in its own frame
// (objects/box_keypoints.h: i-1 in binary is (right, top, front)).
inline Vec3 BoxCorner(int i) {
  if (i == 0) return Vec3::Zero();
  const int b = i - 1;
  return {(b & 4) ? 1.0 : -1.0, (b & 2) ? 1.0 : -1.0, (b & 1) ? 1.0 : -1.0};
}

struct LiftedBox {
  Mat3 R = Mat3::Identity();  // box frame -> camera
  Vec3 t = Vec3::Zero();      // the box centre, camera frame, in units of size's geometric mean
  Vec3 size = Vec3::Ones();   // full extents along the box's x, y, z; geometric mean 1
  double rms_px = 0;          // reprojection RMS of the nine keypoints
  bool degenerate = false;    // the thinnest extent is under degenerate_ratio of the largest
};

// `K` in pixels. Throws Error("bad_keypoints") when the keypoints are not
// finite or the solution lies behind the camera.
LiftedBox LiftBox(const BoxKeypoints& keypoints, const Mat3& K, double degenerate_ratio = 0.2);

// The nine keypoints of a box (extents `size`) at `pose` (box -> camera), projected by K.
BoxKeypoints ProjectBox(const Pose& pose, const Vec3& size, const Mat3& K);

// The box's pose for known extents `size` (Ceres, from `start`): the
// reprojection error of the nine keypoints, or with `axis_only` of the
// centre and the top- and bottom-face centres (a cylinder's axis, which a
// thin-slab reading of a round object still places).
Pose PoseForShape(const BoxKeypoints& keypoints, const Mat3& K, const Vec3& size, const Pose& start,
                  bool axis_only = false);

// A box seen from the side (a round object read as a thin slab): the axis
// from the bottom-face to the top-face centre lies across the view, so its
// image length is fx * height / depth. The centre on keypoint 0's ray at
// that depth, the box's y axis along the image axis, x across it in the
// image plane.
Pose SideViewPose(const BoxKeypoints& keypoints, const Mat3& K, double height);

// The mean of the top face's (y = +1) and the bottom face's keypoints.
Vec2 TopFaceCentre(const BoxKeypoints& keypoints);
Vec2 BottomFaceCentre(const BoxKeypoints& keypoints);

// For a box symmetric about its y axis: the rotation with the same y axis
// whose x axis is nearest the camera's x (else its z): one yaw for every
// frame, since the object shows none.
Mat3 CanonicalYaw(const Mat3& R);

}  // namespace doasido::objects
