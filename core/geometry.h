// Rigid transforms and camera model shared by every module.
// Conventions (REFERENCE.md §3): OpenCV camera axes (x right, y down,
// z forward), metres, pixel centres at integer coordinates, quaternions
// stored w, x, y, z.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

namespace doasido {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;
using Quat = Eigen::Quaterniond;

// A rigid transform x_parent = R * x_child + t.
struct Pose {
  Quat q = Quat::Identity();
  Vec3 t = Vec3::Zero();

  static Pose Identity() { return {}; }
  Mat3 R() const { return q.toRotationMatrix(); }
  Mat4 Matrix() const;
  Vec3 operator*(const Vec3& x) const { return q * x + t; }
  Pose operator*(const Pose& other) const { return {q * other.q, q * other.t + t}; }
  Pose Inverse() const;
};

// The rigid transform minimising sum |pose * a_i - b_i|^2 (Kabsch: SVD of
// the cross-covariance of the centred sets, reflection excluded). a and b
// have the same size, at least 3 points not all on a line.
Pose FitRigid(const std::vector<Vec3>& a, const std::vector<Vec3>& b);

// Angle in radians of the rotation taking a to b, in [0, pi].
double RotationAngle(const Quat& a, const Quat& b);

// q or -q, whichever is nearer `reference` (same rotation; a model that
// treats quaternions as vectors needs one sign for a mode and its target).
Quat SameHemisphere(const Quat& q, const Quat& reference);

// log(2 pi), the Gaussian normalisation constant per dimension.
inline constexpr double kLog2Pi = 1.8378770664093453;

// Pinhole intrinsics in pixels.
struct Camera {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;

  Mat3 K() const;
  static Camera FromK(const Mat3& K, int width, int height);
  // Projects a camera-frame point; z must be > 0.
  Vec2 Project(const Vec3& p) const { return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy}; }
  // The camera-frame point at pixel (u, v) and depth z.
  Vec3 Unproject(double u, double v, double z) const {
    return {(u - cx) / fx * z, (v - cy) / fy * z, z};
  }
};

}  // namespace doasido
