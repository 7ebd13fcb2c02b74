#include "deploy/arm_ik.h"

#include <cmath>
#include <numbers>

#include <ceres/ceres.h>

#include "core/config_check.h"

namespace doasido::deploy {
namespace {

// Residuals: 3 position (m), 9 rotation-matrix entries scaled by rot_scale.
struct FlangeResidual {
  FlangeResidual(const Pose& target, const DhParameters& dh, double rot_scale)
      : p(target.t), r(target.R()), dh(dh), rot_scale(rot_scale) {}

  template <typename T>
  bool operator()(const T* q, T* residual) const {
    const Eigen::Matrix<T, 4, 4> m = DhForward<T>(q, dh);
    for (int i = 0; i < 3; ++i) residual[i] = m(i, 3) - T(p[i]);
    const T w(rot_scale / std::sqrt(2.0));
    for (int c = 0; c < 3; ++c) {
      for (int i = 0; i < 3; ++i) residual[3 + 3 * c + i] = w * (m(i, c) - T(r(i, c)));
    }
    return true;
  }

  Vec3 p;
  Mat3 r;
  DhParameters dh;
  double rot_scale;
};

}  // namespace

void CheckConfig(const IkConfig& c, const std::string& section) {
  RequireInRange(section, "position_tolerance", c.position_tolerance, 1e-9, 1);
  RequireInRange(section, "rotation_tolerance", c.rotation_tolerance, 1e-9, 1);
  RequireInRange(section, "rot_scale", c.rot_scale, 1e-6, 10);
  RequireInRange(section, "restarts", c.restarts, 0, 10000);
  RequireInRange(section, "max_iterations", c.max_iterations, 1, 100000);
}

ArmIk::ArmIk(IkConfig config, DhParameters dh, ArmLimits limits)
    : config_(config), dh_(dh), limits_(limits), rng_(config.seed) {
  CheckConfig(config_, "deploy.ik");
}

IkResult ArmIk::SolveFrom(const Pose& target, const ArmQ& start) {
  IkResult out;
  out.q = start;
  for (int i = 0; i < 6; ++i) out.q[i] = std::clamp(out.q[i], limits_.lower[i], limits_.upper[i]);
  ceres::Problem::Options problem_options;
  ceres::Problem problem(problem_options);
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<FlangeResidual, 12, 6>(
          new FlangeResidual(target, dh_, config_.rot_scale)),
      nullptr, out.q.data());
  for (int i = 0; i < 6; ++i) {
    problem.SetParameterLowerBound(out.q.data(), i, limits_.lower[i]);
    problem.SetParameterUpperBound(out.q.data(), i, limits_.upper[i]);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = config_.max_iterations;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  const Pose reached = DhForwardPose(out.q, dh_);
  out.position_error = (reached.t - target.t).norm();
  out.rotation_error = RotationAngle(reached.q, target.q);
  out.reached = out.position_error <= config_.position_tolerance &&
                out.rotation_error <= config_.rotation_tolerance;
  out.starts = 1;
  return out;
}

IkResult ArmIk::Solve(const Pose& target, const ArmQ& seed) {
  IkResult best = SolveFrom(target, seed);
  best.q = Nearest(best.q, seed);
  int starts = 1;
  for (int r = 0; r < config_.restarts && !best.reached; ++r) {
    IkResult trial = SolveFrom(target, RandomQ());
    ++starts;
    trial.q = Nearest(trial.q, seed);
    const bool better = trial.reached ? (!best.reached || (trial.q - seed).norm() < (best.q - seed).norm())
                                      : (!best.reached && trial.position_error + config_.rot_scale * trial.rotation_error <
                                                              best.position_error + config_.rot_scale * best.rotation_error);
    if (better) best = trial;
  }
  best.starts = starts;
  return best;
}

ArmQ ArmIk::Nearest(ArmQ q, const ArmQ& seed) const {
  constexpr double kTwoPi = 2 * std::numbers::pi;
  for (int i = 0; i < 6; ++i) {
    const double shifted = q[i] + kTwoPi * std::round((seed[i] - q[i]) / kTwoPi);
    if (shifted >= limits_.lower[i] && shifted <= limits_.upper[i]) q[i] = shifted;
  }
  return q;
}

ArmQ ArmIk::RandomQ() {
  ArmQ q;
  for (int i = 0; i < 6; ++i) {
    // Random starts within one turn: the limits span two, and the other
    // representation is reached by Nearest.
    std::uniform_real_distribution<double> u(std::max(limits_.lower[i], -std::numbers::pi),
                                             std::min(limits_.upper[i], std::numbers::pi));
    q[i] = u(rng_);
  }
  return q;
}

}  // namespace doasido::deploy
