// The metric size of a lifted box. One view gives a box's pose and
// proportions up to one scale λ (the box's extents λ p, its centre λ t̂);
// the hand is metric (the method takes the hand's scale as truth, seed
// §3.1). Where fingertips touch the object, λ is the one that puts them on
// its surface: minimise, over every touching fingertip f of every frame,
// the Cauchy-weighted (d(f; λ) - offset)², d the distance from f to the
// surface of the box (a capped cylinder for round objects) of extents λ p at
// pose (R, λ t̂), offset the distance from the tip keypoint to the skin that
// touches. A 1-D search over log λ finds the basin, Ceres refines it.
#pragma once

#include <vector>

#include "core/geometry.h"

namespace doasido::objects {

// One frame's box up to scale: rotation, and the centre in units where the
// extents are `shape` (geometric mean 1).
struct UnitPose {
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
};

// A fingertip (camera frame, metres) seen touching the box of frame `pose`.
struct FingertipContact {
  int pose = 0;  // index into the poses
  Vec3 fingertip = Vec3::Zero();
};

struct ContactScaleConfig {
  double fingertip_offset_m = 0.008;  // tip keypoint to the touching skin
  double robust_m = 0.01;             // Cauchy scale of a fingertip's residual
  double search_min = 0.25;           // λ searched over [min, max] times the start
  double search_max = 4.0;
};

struct ContactScale {
  double scale = 0;              // λ: the box's extents are λ shape, metres
  double residual_median_m = 0;  // median |d - offset| at λ
};

// Signed distance from `q` (box frame) to the surface of a box of full
// extents `size`, or of the capped cylinder along y of diameter size.x()
// and height size.y() when `cylinder`; negative inside.
double SurfaceDistance(const Vec3& q, const Vec3& size, bool cylinder);

// λ for `shape` from the contacts (at least one), starting the search at
// `start` (the category prior's λ).
ContactScale FitContactScale(const std::vector<UnitPose>& poses, const Vec3& shape, bool cylinder,
                             const std::vector<FingertipContact>& contacts, double start,
                             const ContactScaleConfig& config);

}  // namespace doasido::objects
