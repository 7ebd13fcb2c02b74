#include "core/geometry.h"

#include <algorithm>
#include <cmath>

#include <Eigen/SVD>

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

Pose FitRigid(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  Vec3 ca = Vec3::Zero(), cb = Vec3::Zero();
  for (size_t i = 0; i < a.size(); ++i) {
    ca += a[i];
    cb += b[i];
  }
  ca /= static_cast<double>(a.size());
  cb /= static_cast<double>(b.size());
  Mat3 h = Mat3::Zero();
  for (size_t i = 0; i < a.size(); ++i) h += (a[i] - ca) * (b[i] - cb).transpose();
  Eigen::JacobiSVD<Mat3> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 d = Mat3::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  const Mat3 r = svd.matrixV() * d * svd.matrixU().transpose();
  return {Quat(r), cb - r * ca};
}

Quat SameHemisphere(const Quat& q, const Quat& reference) {
  return q.dot(reference) < 0 ? Quat(-q.w(), -q.x(), -q.y(), -q.z()) : q;
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
