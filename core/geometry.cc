#include "core/geometry.h"

#include <algorithm>
#include <cmath>

namespace doasido {

Mat4 Pose::Matrix() const {
  Mat4 m = Mat4::Identity();
  m.topLeftCorner<3, 3>() = R();
  m.topRightCorner<3, 1>() = t;
  return m;
}

Pose Pose::Inverse() const {
  const Quat qi = q.conjugate();
  return {qi, -(qi * t)};
}

double RotationAngle(const Quat& a, const Quat& b) {
  const double d = std::abs(a.normalized().dot(b.normalized()));
  return 2.0 * std::acos(std::clamp(d, 0.0, 1.0));
}

Mat3 Camera::K() const {
  Mat3 k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

Camera Camera::FromK(const Mat3& K, int w, int h) {
  return {w, h, K(0, 0), K(1, 1), K(0, 2), K(1, 2)};
}

}  // namespace doasido
