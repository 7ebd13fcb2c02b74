#include "deploy/arm_ik.h"

#include <cmath>
#include <limits>
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

// DH link i's transform at joint angle q (ur3e.h's product, one factor).
Mat4 DhLink(int i, double q, const DhParameters& dh) {
  const double c = std::cos(q), s = std::sin(q), ca = std::cos(dh.alpha[i]), sa = std::sin(dh.alpha[i]);
  Mat4 m;
  m << c, -s * ca, s * sa, dh.a[i] * c,
       s, c * ca, -c * sa, dh.a[i] * s,
       0, sa, ca, dh.d[i],
       0, 0, 0, 1;
  return m;
}

Mat4 InverseRigid(const Mat4& m) {
  Mat4 out = Mat4::Identity();
  out.topLeftCorner<3, 3>() = m.topLeftCorner<3, 3>().transpose();
  out.topRightCorner<3, 1>() = -m.topLeftCorner<3, 3>().transpose() * m.topRightCorner<3, 1>();
  return out;
}

double Wrap(double a) { return std::remainder(a, 2 * std::numbers::pi); }

// acos of a cosine that rounding may have put just outside [-1, 1]; NaN
// when it is really outside (the branch does not exist).
double AcosWithin(double c) {
  constexpr double kSlack = 1e-9;
  return std::abs(c) > 1 + kSlack ? std::nan("") : std::acos(std::clamp(c, -1.0, 1.0));
}

// Elbow and the rest, given the shoulder pan q1, wrist_2 q5 and wrist_3
// q6: the planar shoulder-elbow pair reaches the origin of frame 3.
void AppendElbowBranches(const Mat4& t06, double q1, double q5, double q6, const DhParameters& dh,
                         std::vector<ArmQ>& out) {
  const Mat4 t14 = InverseRigid(DhLink(0, q1, dh)) * t06 * InverseRigid(DhLink(5, q6, dh)) *
                   InverseRigid(DhLink(4, q5, dh));
  // Frame 3's origin in frame 1: frame 4's, back d4 along z3 (= y4).
  const Vec3 p13 = (t14 * Eigen::Vector4d(0, -dh.d[3], 0, 1)).head<3>();
  const double a2 = dh.a[1], a3 = dh.a[2];
  const double elbow = AcosWithin((p13.squaredNorm() - a2 * a2 - a3 * a3) / (2 * a2 * a3));
  if (std::isnan(elbow)) return;
  for (const double q3 : {elbow, -elbow}) {
    const double q2 = std::atan2(p13.y(), p13.x()) - std::atan2(a3 * std::sin(q3), a2 + a3 * std::cos(q3));
    const Mat4 t34 = InverseRigid(DhLink(2, q3, dh)) * InverseRigid(DhLink(1, q2, dh)) * t14;
    const double q4 = std::atan2(t34(1, 0), t34(0, 0));
    ArmQ q;
    q << Wrap(q1), Wrap(q2), Wrap(q3), Wrap(q4), Wrap(q5), Wrap(q6);
    out.push_back(q);
    if (elbow == 0) return;  // one solution, not two
  }
}

}  // namespace

std::vector<ArmQ> ClosedFormIk(const Pose& target, double q6_free, const DhParameters& dh) {
  std::vector<ArmQ> out;
  const Mat4 t06 = target.Matrix();
  const Mat3 r = target.R();
  const Vec3 p5 = target.t - dh.d[5] * r.col(2);  // the wrist_2 axis' point
  const double reach = std::hypot(p5.x(), p5.y());
  const double shoulder = reach > 0 ? AcosWithin(dh.d[3] / reach) : std::nan("");
  if (std::isnan(shoulder)) return out;  // within the d4 cylinder about the base axis
  const double phi = std::atan2(p5.y(), p5.x());
  for (const double q1 : {phi + shoulder + std::numbers::pi / 2, phi - shoulder + std::numbers::pi / 2}) {
    const double s1 = std::sin(q1), c1 = std::cos(q1);
    const double wrist = AcosWithin((target.t.x() * s1 - target.t.y() * c1 - dh.d[3]) / dh.d[5]);
    if (std::isnan(wrist)) continue;
    for (const double q5 : {wrist, -wrist}) {
      const double s5 = std::sin(q5);
      constexpr double kWristSingular = 1e-9;
      // Frame 0's x and y axes seen from frame 6 are the rows of r.
      const double q6 = std::abs(s5) < kWristSingular
                            ? q6_free
                            : std::atan2((-r(0, 1) * s1 + r(1, 1) * c1) / s5, (r(0, 0) * s1 - r(1, 0) * c1) / s5);
      AppendElbowBranches(t06, q1, q5, q6, dh, out);
      if (wrist == 0) break;
    }
    if (shoulder == 0) break;
  }
  return out;
}

double JointDistance(const ArmQ& a, const ArmQ& b, const ArmLimits& limits) {
  double sum = 0;
  for (int i = 0; i < 6; ++i) sum += std::pow((a[i] - b[i]) / limits.max_speed[i], 2);
  return std::sqrt(sum);
}

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
  Restart(target, seed, best, starts);
  best.starts = starts;
  return best;
}

void ArmIk::Restart(const Pose& target, const ArmQ& seed, IkResult& best, int& starts) {
  for (int r = 0; r < config_.restarts && !best.reached; ++r) {
    IkResult trial = SolveFrom(target, RandomQ());
    ++starts;
    trial.q = Nearest(trial.q, seed);
    const bool better = trial.reached ? (!best.reached || (trial.q - seed).norm() < (best.q - seed).norm())
                                      : (!best.reached && trial.position_error + config_.rot_scale * trial.rotation_error <
                                                              best.position_error + config_.rot_scale * best.rotation_error);
    if (better) best = trial;
  }
}

std::vector<IkResult> ArmIk::SolveChain(const std::vector<Pose>& targets, const ArmQ& start) {
  std::vector<IkResult> chain;
  ArmQ q = start;
  for (const Pose& target : targets) {
    chain.push_back(Solve(target, q));
    q = chain.back().q;
  }
  return chain;
}

std::vector<IkResult> ArmIk::LeastMotionPath(const std::vector<Pose>& targets, const ArmQ& start) {
  struct State {
    ArmQ q;
    double cost = 0;
    int back = -1;  // the state of the frame before
  };
  const auto step = [&](const ArmQ& a, const ArmQ& b) { return std::pow(JointDistance(a, b, limits_), 2); };
  std::vector<std::vector<State>> states;
  for (const Pose& target : targets) {
    // The first frame's branch is free (the lead-in moves the arm there
    // from home, off the path): only the path's own motion counts.
    const std::vector<State> before = states.empty() ? std::vector<State>{{start}} : states.back();
    const bool first = states.empty();
    std::vector<State> here;
    for (const ArmQ& solution : ClosedFormIk(target, before[0].q[5], dh_)) {
      State best{.cost = std::numeric_limits<double>::infinity()};
      for (int b = 0; b < static_cast<int>(before.size()); ++b) {
        const ArmQ q = Nearest(solution, before[b].q);
        const double cost = first ? 0.0 : before[b].cost + step(q, before[b].q);
        if (WithinLimits(q) && cost < best.cost) best = {q, cost, first ? -1 : b};
      }
      if (std::isfinite(best.cost)) here.push_back(best);
    }
    // Out of the closed form's reach: each branch's nearest answer (least
    // squares from it), so the path stays continuous through the frames
    // it cannot reach; a random start reaching the pose just past the exact
    // reach would do so on another branch, a jump.
    if (here.empty()) {
      for (int b = 0; b < static_cast<int>(before.size()); ++b) {
        const ArmQ q = Nearest(SolveFrom(target, before[b].q).q, before[b].q);
        here.push_back({q, first ? 0.0 : before[b].cost + step(q, before[b].q), first ? -1 : b});
      }
    }
    states.push_back(std::move(here));
  }
  std::vector<IkResult> out(targets.size());
  if (states.empty()) return out;
  int s = 0;
  for (int i = 1; i < static_cast<int>(states.back().size()); ++i) {
    if (states.back()[i].cost < states.back()[s].cost) s = i;
  }
  for (int f = static_cast<int>(states.size()) - 1; f >= 0; --f) {
    out[f] = Exact(targets[f], states[f][s].q);
    s = states[f][s].back;
  }
  return out;
}

IkResult ArmIk::Exact(const Pose& target, const ArmQ& q) const {
  IkResult r;
  r.q = q;
  const Pose reached = DhForwardPose(q, dh_);
  r.position_error = (reached.t - target.t).norm();
  r.rotation_error = RotationAngle(reached.q, target.q);
  r.reached = r.position_error <= config_.position_tolerance && r.rotation_error <= config_.rotation_tolerance;
  return r;
}

bool ArmIk::WithinLimits(const ArmQ& q) const {
  for (int i = 0; i < 6; ++i) {
    if (q[i] < limits_.lower[i] || q[i] > limits_.upper[i]) return false;
  }
  return true;
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
