// SmoothScales (declared in recon/align/hand_object_alignment.h): the optional
// temporal re-solve of the per-frame translation scales as one Ceres problem.
#include <cmath>
#include <limits>

#include <ceres/ceres.h>

#include "recon/align/hand_object_alignment.h"

namespace doasido::recon {
namespace {

// c_mesh + s t - target, metres.
struct FrameResidual {
  Vec3 t, c_mesh, target;
  template <typename T>
  bool operator()(const T* s, T* r) const {
    for (int i = 0; i < 3; ++i) r[i] = T(c_mesh[i]) + s[0] * T(t[i]) - T(target[i]);
    return true;
  }
};

// w (s0 t0 - 2 s1 t1 + s2 t2): the acceleration of the scaled object origin.
struct AccelerationResidual {
  Vec3 t0, t1, t2;
  double w;
  template <typename T>
  bool operator()(const T* s0, const T* s1, const T* s2, T* r) const {
    for (int i = 0; i < 3; ++i) {
      r[i] = T(w) * (s0[0] * T(t0[i]) - 2.0 * s1[0] * T(t1[i]) + s2[0] * T(t2[i]));
    }
    return true;
  }
};

}  // namespace

std::vector<double> SmoothScales(const HandObjectAlignment& a, const std::vector<Pose>& poses,
                                 const HandObjectAlignmentConfig& config) {
  std::vector<double> s = a.scale;
  ceres::Problem problem;
  const int T = static_cast<int>(s.size());
  for (int t = 0; t < T; ++t) {
    const FrameAlignment& f = a.frames[t];
    if (!std::isfinite(s[t]) || !f.aligned) continue;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<FrameResidual, 3, 1>(
                                 new FrameResidual{poses[t].t, f.c_mesh, f.target}),
                             new ceres::HuberLoss(config.robust_scale), &s[t]);
  }
  for (int t = 1; t + 1 < T; ++t) {
    if (!std::isfinite(s[t - 1]) || !std::isfinite(s[t]) || !std::isfinite(s[t + 1])) continue;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<AccelerationResidual, 3, 1, 1, 1>(new AccelerationResidual{
            poses[t - 1].t, poses[t].t, poses[t + 1].t, config.smooth_weight}),
        nullptr, &s[t - 1], &s[t], &s[t + 1]);
  }
  if (problem.NumResidualBlocks() == 0) return s;
  for (double& x : s) {
    if (problem.HasParameterBlock(&x)) problem.SetParameterLowerBound(&x, 0, 1e-3);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = 50;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return s;
}

}  // namespace doasido::recon
