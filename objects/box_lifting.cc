#include "objects/box_lifting.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "core/error.h"
#include "objects/ceres_geometry.h"

namespace doasido::objects {
namespace {

// Keypoint i's weights on the control points c0..c3 (file comment).
Eigen::Vector4d Alpha(int i) {
  const Vec3 s = BoxCorner(i);
  return {1 - s.x() - s.y() - s.z(), s.x(), s.y(), s.z()};
}

// The rotation nearest `A` (SVD), never a reflection.
Mat3 NearestRotation(const Mat3& A) {
  Eigen::JacobiSVD<Mat3> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 D = Mat3::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) D(2, 2) = -1;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

// A keypoint of a box whose extents are exp(a), exp(b), exp(-a-b) (the
// geometric mean held at 1: the one gauge of a single view).
struct FreeBoxResidual {
  FreeBoxResidual(int i, const Vec2& uv, const Mat3& K) : corner(BoxCorner(i) / 2), uv(uv), K(K) {}
  template <typename T>
  bool operator()(const T* aa, const T* t, const T* log_size, T* r) const {
    using std::exp;
    const T s[3] = {exp(log_size[0]), exp(log_size[1]), exp(-log_size[0] - log_size[1])};
    const T p[3] = {T(corner.x()) * s[0], T(corner.y()) * s[1], T(corner.z()) * s[2]};
    T q[3];
    ceres::AngleAxisRotatePoint(aa, p, q);
    for (int k = 0; k < 3; ++k) q[k] += t[k];
    r[0] = T(K(0, 0)) * q[0] / q[2] + T(K(0, 1)) * q[1] / q[2] + T(K(0, 2)) - T(uv.x());
    r[1] = T(K(1, 1)) * q[1] / q[2] + T(K(1, 2)) - T(uv.y());
    return true;
  }
  Vec3 corner;
  Vec2 uv;
  Mat3 K;
};

double RmsPx(const BoxKeypoints& keypoints, const Pose& pose, const Vec3& size, const Mat3& K) {
  const BoxKeypoints projected = ProjectBox(pose, size, K);
  double sum = 0;
  for (int i = 0; i < kBoxKeypoints; ++i) sum += (projected[i] - keypoints[i]).squaredNorm();
  return std::sqrt(sum / kBoxKeypoints);
}

}  // namespace

BoxKeypoints ProjectBox(const Pose& pose, const Vec3& size, const Mat3& K) {
  BoxKeypoints out;
  for (int i = 0; i < kBoxKeypoints; ++i) {
    const Vec3 p = pose * Vec3(BoxCorner(i).cwiseProduct(size) / 2);
    const Vec3 h = K * p;
    out[i] = h.head<2>() / h.z();
  }
  return out;
}

LiftedBox LiftBox(const BoxKeypoints& keypoints, const Mat3& K, double degenerate_ratio) {
  for (const Vec2& p : keypoints) {
    if (!p.allFinite()) throw Error("bad_keypoints", "a box keypoint is not finite");
  }
  // Two rows per keypoint: fx X + (cx - u) Z = 0 and fy Y + (cy - v) Z = 0
  // for X = sum_j alpha_j c_j (the skew K(0,1) folded into the first row).
  using MMatrix = Eigen::Matrix<double, 2 * kBoxKeypoints, 12>;
  MMatrix M = MMatrix::Zero();
  for (int i = 0; i < kBoxKeypoints; ++i) {
    const Eigen::Vector4d a = Alpha(i);
    const Vec2& uv = keypoints[i];
    for (int j = 0; j < 4; ++j) {
      M(2 * i, 3 * j) = K(0, 0) * a[j];
      M(2 * i, 3 * j + 1) = K(0, 1) * a[j];
      M(2 * i, 3 * j + 2) = (K(0, 2) - uv.x()) * a[j];
      M(2 * i + 1, 3 * j + 1) = K(1, 1) * a[j];
      M(2 * i + 1, 3 * j + 2) = (K(1, 2) - uv.y()) * a[j];
    }
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 12, 12>> eig(M.transpose() * M);
  Eigen::Matrix<double, 12, 1> v = eig.eigenvectors().col(0);  // eigenvalues ascend
  if (v[2] < 0) v = -v;                                          // the centre in front
  const Vec3 c0 = v.segment<3>(0);
  Mat3 axes;  // half-axes as columns
  for (int j = 0; j < 3; ++j) axes.col(j) = v.segment<3>(3 * (j + 1)) - c0;
  Vec3 half = axes.colwise().norm().transpose();
  if (c0.z() <= 0 || half.minCoeff() <= 0) {
    throw Error("bad_keypoints", "the box's keypoints lift to no box in front of the camera");
  }
  // Start the refinement from the affine box's nearest rotation and extents.
  Mat3 unit_axes = axes;
  for (int j = 0; j < 3; ++j) unit_axes.col(j) /= half[j];
  Vec3 aa = AngleAxisOf(NearestRotation(unit_axes));
  const double g = std::cbrt(8 * half.prod());
  Vec3 t = c0 / g;
  const Vec3 log_size = (2 * half / g).array().log();
  double ls[2] = {log_size.x(), log_size.y()};
  ceres::Problem problem;
  for (int i = 0; i < kBoxKeypoints; ++i) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<FreeBoxResidual, 2, 3, 3, 2>(
                                 new FreeBoxResidual(i, keypoints[i], K)),
                             nullptr, aa.data(), t.data(), ls);
  }
  SolveToConvergence(problem);
  LiftedBox out;
  out.R = RotationOf(aa);
  out.t = t;
  out.size = Vec3(std::exp(ls[0]), std::exp(ls[1]), std::exp(-ls[0] - ls[1]));
  out.rms_px = RmsPx(keypoints, {Quat(out.R), out.t}, out.size, K);
  out.degenerate = out.size.minCoeff() < degenerate_ratio * out.size.maxCoeff();
  if (out.t.z() <= 0) {
    throw Error("bad_keypoints", "the box's keypoints lift to no box in front of the camera");
  }
  return out;
}

Vec2 TopFaceCentre(const BoxKeypoints& k) { return (k[3] + k[4] + k[7] + k[8]) / 4; }
Vec2 BottomFaceCentre(const BoxKeypoints& k) { return (k[1] + k[2] + k[5] + k[6]) / 4; }

Pose PoseForShape(const BoxKeypoints& keypoints, const Mat3& K, const Vec3& size, const Pose& start,
                  bool axis_only) {
  Vec3 aa = AngleAxisOf(start.R());
  Vec3 t = start.t;
  ceres::Problem problem;
  auto add = [&](const Vec3& x, const Vec2& uv) {
    problem.AddResidualBlock(PointResidual::Create(x, uv, K), nullptr, aa.data(), t.data());
  };
  if (axis_only) {
    add(Vec3::Zero(), keypoints[0]);
    add(Vec3(0, size.y() / 2, 0), TopFaceCentre(keypoints));
    add(Vec3(0, -size.y() / 2, 0), BottomFaceCentre(keypoints));
  } else {
    for (int i = 0; i < kBoxKeypoints; ++i) add(BoxCorner(i).cwiseProduct(size) / 2, keypoints[i]);
  }
  SolveToConvergence(problem);
  return {Quat(RotationOf(aa)), t};
}

Pose SideViewPose(const BoxKeypoints& keypoints, const Mat3& K, double height) {
  const Mat3 Kinv = K.inverse();
  const Vec2 top = TopFaceCentre(keypoints), bottom = BottomFaceCentre(keypoints);
  const double length_px = std::max((top - bottom).norm(), 1e-6);
  const double depth = K(0, 0) * height / length_px;
  const Vec3 centre = Kinv * Vec3(keypoints[0].x(), keypoints[0].y(), 1.0) * depth;
  // The image axis at the centre's depth, then square to the viewing ray.
  const Vec3 a = Kinv * Vec3(top.x(), top.y(), 1.0) - Kinv * Vec3(bottom.x(), bottom.y(), 1.0);
  const Vec3 ray = centre.normalized();
  Vec3 y = (a - a.dot(ray) * ray).normalized();
  Mat3 R;
  R.col(1) = y;
  R.col(2) = -ray;  // the front face toward the camera
  R.col(0) = R.col(1).cross(R.col(2));
  return {Quat(CanonicalYaw(R)), centre};
}

Mat3 CanonicalYaw(const Mat3& R) {
  const Vec3 y = R.col(1).normalized();
  Vec3 x = Vec3::UnitX() - Vec3::UnitX().dot(y) * y;
  if (x.norm() < 0.1) x = Vec3::UnitZ() - Vec3::UnitZ().dot(y) * y;
  x.normalize();
  Mat3 out;
  out.col(0) = x;
  out.col(1) = y;
  out.col(2) = x.cross(y);
  return out;
}

}  // namespace doasido::objects
