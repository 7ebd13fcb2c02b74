// Internal to objects/: the Ceres pieces its solvers share (the lifting,
// the contact scale and the track fit): a box-frame point's reprojection
// residual, angle-axis conversions and a solve run to convergence.
#pragma once

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "core/geometry.h"

namespace doasido::objects {

// Pixel error of a known point x of the object's frame, posed by angle-axis
// aa and translation t and projected by K, against its keypoint uv, in
// units of sigma pixels.
struct PointResidual {
  template <typename T>
  bool operator()(const T* aa, const T* t, T* r) const {
    const T p[3] = {T(x.x()), T(x.y()), T(x.z())};
    T q[3];
    ceres::AngleAxisRotatePoint(aa, p, q);
    for (int k = 0; k < 3; ++k) q[k] += t[k];
    r[0] = (T(K(0, 0)) * q[0] / q[2] + T(K(0, 1)) * q[1] / q[2] + T(K(0, 2)) - T(uv.x())) / T(sigma);
    r[1] = (T(K(1, 1)) * q[1] / q[2] + T(K(1, 2)) - T(uv.y())) / T(sigma);
    return true;
  }
  static ceres::CostFunction* Create(const Vec3& x, const Vec2& uv, const Mat3& K, double sigma = 1) {
    return new ceres::AutoDiffCostFunction<PointResidual, 2, 3, 3>(new PointResidual{x, uv, K, sigma});
  }
  Vec3 x;
  Vec2 uv;
  Mat3 K;
  double sigma = 1;
};

inline Vec3 AngleAxisOf(const Mat3& R) {
  Vec3 aa;
  ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(R.data()), aa.data());
  return aa;
}

inline Mat3 RotationOf(const Vec3& aa) {
  Mat3 R;
  ceres::AngleAxisToRotationMatrix(aa.data(), ceres::ColumnMajorAdapter3x3(R.data()));
  return R;
}

// Solves a small problem to the numbers' precision (exact inputs give
// exact answers: the tests hold the solvers to 1e-6).
inline void SolveToConvergence(ceres::Problem& problem) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  options.gradient_tolerance = 1e-16;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
}

}  // namespace doasido::objects
