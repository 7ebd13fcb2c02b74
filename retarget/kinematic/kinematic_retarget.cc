#include "retarget/kinematic/kinematic_retarget.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>

#include <ceres/ceres.h>
#include <Eigen/SVD>
#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/stage_progress.h"

namespace doasido::retarget {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool IsPalmKeypoint(int k) { return k == 0 || k == 5 || k == 9 || k == 13 || k == 17; }

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

double WrapAngle(double a) { return std::remainder(a, 2 * M_PI); }

// x, y, z angles with R = Rx(a) Ry(b) Rz(c) (MuJoCo's order for hinge joints
// declared x, y, z in one body), the smaller of the two equivalent triples.
Vec3 EulerXYZ(const Mat3& r) {
  const Vec3 e = r.eulerAngles(0, 1, 2);
  Vec3 a(WrapAngle(e[0]), WrapAngle(e[1]), WrapAngle(e[2]));
  Vec3 b(WrapAngle(e[0] + M_PI), WrapAngle(M_PI - e[1]), WrapAngle(e[2] + M_PI));
  return a.norm() <= b.norm() ? a : b;
}

}  // namespace

KinematicRetargeter::KinematicRetargeter(const HandModel& hand, KinematicConfig config)
    : hand_(hand), config_(config), data_(MakeData(hand.model.get())),
      surface_(hand.model.get(), NameToId(hand.model.get(), mjOBJ_BODY, "object")), rng_(config.seed) {
  const mjModel* m = hand_.model.get();
  const int object = NameToId(m, mjOBJ_BODY, "object");
  if (object >= 0 && m->body_jntnum[object] == 1 && m->jnt_type[m->body_jntadr[object]] == mjJNT_FREE) {
    object_qpos_ = m->jnt_qposadr[m->body_jntadr[object]];
  }
  if (hand_.wrist_qpos.size() != 6) {
    throw Error("bad_embodiment", "kinematic retargeting needs the floating wrist",
                {.field = "floating_base"});
  }
  std::vector<int> qadr = hand_.wrist_qpos;
  qadr.insert(qadr.end(), hand_.finger_qpos.begin(), hand_.finger_qpos.end());
  const int n = static_cast<int>(qadr.size());
  lower_ = Eigen::VectorXd::Constant(n, -kInf);
  upper_ = Eigen::VectorXd::Constant(n, kInf);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < m->njnt; ++j) {
      if (m->jnt_qposadr[j] != qadr[k]) continue;
      qpos_adr_.push_back(qadr[k]);
      dof_adr_.push_back(m->jnt_dofadr[j]);
      if (m->jnt_limited[j]) {
        lower_[k] = m->jnt_range[2 * j];
        upper_[k] = m->jnt_range[2 * j + 1];
      }
    }
  }
  for (int i = 0; i < static_cast<int>(hand_.points.size()); ++i) {
    if (config_.use_intermediate || hand_.points[i].fingertip || hand_.points[i].keypoint == 0) {
      active_.push_back(i);
    }
    if (IsPalmKeypoint(hand_.points[i].keypoint)) palm_points_.push_back(i);
  }
  tip_geom_.assign(active_.size(), -1);
  for (int g = 0; g < m->ngeom; ++g) {
    const int body = m->geom_bodyid[g];
    if (body == 0 || body == object || !(m->geom_contype[g] | m->geom_conaffinity[g]) ||
        !ObjectSurface::Measures(m, g)) {
      continue;
    }
    hand_geoms_.push_back(g);
  }
  for (size_t a = 0; a < active_.size(); ++a) {  // a fingertip's geom: the one nearest its site
    const ModelPoint& p = hand_.points[active_[a]];
    if (p.site < 0 || !p.fingertip) continue;
    double nearest = kInf;
    for (int g : hand_geoms_) {
      if (m->geom_bodyid[g] != m->site_bodyid[p.site]) continue;
      const double dist = (Eigen::Map<const Vec3>(m->geom_pos + 3 * g) -
                           Eigen::Map<const Vec3>(m->site_pos + 3 * p.site)).norm();
      if (dist < nearest) nearest = dist, tip_geom_[a] = g;
    }
  }
  if (palm_points_.size() < 3) {
    palm_points_.clear();
    for (int i = 0; i < static_cast<int>(hand_.points.size()); ++i) palm_points_.push_back(i);
  }
  Eigen::VectorXd zero(n);
  for (int k = 0; k < n; ++k) zero[k] = k < 6 ? 0.0 : m->qpos0[qpos_adr_[k]];
  Clamp(zero);
  const std::vector<Vec3> at_zero = Points(zero);
  for (int i : palm_points_) palm_at_zero_.push_back(at_zero[i]);
  scale_ = config_.scale > 0 ? config_.scale : hand_.embodiment.scale > 0 ? hand_.embodiment.scale : 1.0;
}

std::vector<std::string> KinematicRetargeter::VariableNames() const {
  const std::vector<std::string> all = QposNames(hand_.model.get());
  std::vector<std::string> out;
  for (int adr : qpos_adr_) out.push_back(all[adr]);
  return out;
}

void KinematicRetargeter::Clamp(Eigen::VectorXd& q) const {
  q = q.cwiseMax(lower_).cwiseMin(upper_);
}

std::vector<Vec3> KinematicRetargeter::Points(const Eigen::VectorXd& q) {
  const mjModel* m = hand_.model.get();
  mjData* d = data_.get();
  for (size_t k = 0; k < qpos_adr_.size(); ++k) d->qpos[qpos_adr_[k]] = q[k];
  mj_kinematics(m, d);
  std::vector<Vec3> out;
  for (const ModelPoint& p : hand_.points) out.push_back(PointPosition(m, d, p));
  return out;
}

Keypoints21 KinematicRetargeter::Reference(const Keypoints21& human) const {
  const Eigen::RowVector3d wrist = human.row(0);
  return (scale_ * (human.rowwise() - wrist)).rowwise() + wrist;
}

std::vector<Vec3> KinematicRetargeter::Targets(const Keypoints21& human) const {
  const Keypoints21 reference = Reference(human);
  std::vector<Vec3> out;
  for (const ModelPoint& p : hand_.points) out.push_back(reference.row(p.keypoint).transpose());
  return out;
}

double KinematicRetargeter::AdaptScale(const std::vector<Keypoints21>& human) {
  if (config_.scale > 0) return scale_ = config_.scale;
  if (hand_.embodiment.scale > 0) return scale_ = hand_.embodiment.scale;
  const mjModel* m = hand_.model.get();
  Eigen::VectorXd zero(qpos_adr_.size());
  for (size_t k = 0; k < qpos_adr_.size(); ++k) zero[k] = k < 6 ? 0.0 : m->qpos0[qpos_adr_[k]];
  Clamp(zero);
  const std::vector<Vec3> robot = Points(zero);
  auto find = [&](int keypoint) {
    for (size_t i = 0; i < hand_.points.size(); ++i) {
      if (hand_.points[i].keypoint == keypoint) return static_cast<int>(i);
    }
    return -1;
  };
  const int wrist = find(0);
  double robot_sum = 0, human_sum = 0;
  for (int f = 1; f < 5; ++f) {  // index, middle, ring, pinky: keypoints 4f+1 .. 4f+4
    const int mcp_k = 4 * f + 1, tip_k = 4 * f + 4;
    const int tip = find(tip_k), mcp = find(mcp_k);
    if (wrist < 0 || tip < 0) continue;
    robot_sum += mcp >= 0 ? (robot[mcp] - robot[wrist]).norm() + (robot[tip] - robot[mcp]).norm()
                          : (robot[tip] - robot[wrist]).norm();
    std::vector<double> lengths;
    for (const Keypoints21& h : human) {
      double len = (h.row(mcp_k) - h.row(0)).norm();
      for (int k = mcp_k; k < tip_k; ++k) len += (h.row(k + 1) - h.row(k)).norm();
      if (std::isfinite(len) && len > 0) lengths.push_back(len);
    }
    human_sum += Median(lengths);
  }
  if (robot_sum > 0 && human_sum > 0) scale_ = robot_sum / human_sum;
  return scale_;
}

// Forward kinematics, point Jacobians (mj_jac) and grasp terms of every
// matched point at one q, computed once however many residual blocks ask.
// The solver's variables are the `free` entries of q (the rest held at
// `base`), so held joints cost no Jacobian columns. Jacobians are computed
// only when asked for: Ceres evaluates a trial step's residuals alone and
// asks for Jacobians only where it accepts the step, so a rejected step
// costs one mj_kinematics and no mj_comPos / mj_jac.
class KinematicRetargeter::PointEvaluator {
 public:
  PointEvaluator(KinematicRetargeter& r, const std::vector<Vec3>& targets, const Eigen::VectorXd& base,
                 std::vector<int> free)
      : r_(r), targets_(targets), q_(base), free_(std::move(free)), n_(static_cast<int>(free_.size())),
        jacp_(3 * r.hand_.model->nv), residual_(r.active_.size()), jacobian_(r.active_.size()),
        surface_residual_(r.geom_terms_.size(), 0.0), surface_jacobian_(r.geom_terms_.size()),
        witness_(r.geom_terms_.size()), normal_(r.geom_terms_.size()) {}

  // Residual (3) and, when `jacobian` is set, its row-major 3 x num_free
  // Jacobian of matched point `i` (index into active_) at the free variables x.
  void Evaluate(const double* x, int i, double* residual, double* jacobian) {
    Update(x, jacobian != nullptr);
    std::copy(residual_[i].data(), residual_[i].data() + 3, residual);
    if (jacobian) std::copy(jacobian_[i].begin(), jacobian_[i].end(), jacobian);
  }
  // The residual (1) of grasp term `i` (index into geom_terms_) and its 1 x num_free Jacobian.
  void EvaluateSurface(const double* x, int i, double* residual, double* jacobian) {
    Update(x, jacobian != nullptr);
    *residual = surface_residual_[i];
    if (jacobian) std::copy(surface_jacobian_[i].begin(), surface_jacobian_[i].end(), jacobian);
  }

  // The stacked residual at q (all variables free): points, grasp terms in
  // use, then smoothness.
  double Stack(const Eigen::VectorXd& q, const Eigen::VectorXd* previous, Eigen::VectorXd* residual,
               Eigen::MatrixXd* jacobian) {
    Update(q.data(), jacobian != nullptr);
    const int points = 3 * static_cast<int>(residual_.size());
    const int surface = static_cast<int>(surface_residual_.size());
    const int rows = points + surface + (previous ? n_ : 0);
    Eigen::VectorXd r(rows);
    for (size_t a = 0; a < residual_.size(); ++a) r.segment<3>(3 * a) = residual_[a];
    for (int s = 0; s < surface; ++s) r[points + s] = surface_residual_[s];
    const double w = std::sqrt(r_.config_.smooth_weight);
    if (previous) r.tail(n_) = w * (q - *previous);
    if (jacobian) {
      Eigen::MatrixXd& j = *jacobian;
      j = Eigen::MatrixXd::Zero(rows, n_);
      for (size_t a = 0; a < residual_.size(); ++a) {
        j.middleRows<3>(3 * a) =
            Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>>(jacobian_[a].data(), 3, n_);
      }
      for (int s = 0; s < surface; ++s) {
        j.row(points + s) = Eigen::Map<const Eigen::RowVectorXd>(surface_jacobian_[s].data(), n_);
      }
      if (previous) j.bottomRows(n_).diagonal().setConstant(w);
    }
    if (residual) *residual = r;
    return r.squaredNorm();
  }

 private:
  // Poses the hand at x (residuals), then, when asked, the Jacobians there.
  void Update(const double* x, bool with_jacobians) {
    if (!posed_ || !std::equal(x, x + n_, last_.begin())) Pose(x);
    if (with_jacobians && !jacobians_) Jacobians();
  }

  void Pose(const double* x) {
    const mjModel* m = r_.hand_.model.get();
    mjData* d = r_.data_.get();
    for (int f = 0; f < n_; ++f) q_[free_[f]] = x[f];
    for (int k = 0; k < static_cast<int>(q_.size()); ++k) d->qpos[r_.qpos_adr_[k]] = q_[k];
    mj_kinematics(m, d);
    for (size_t a = 0; a < r_.active_.size(); ++a) {
      const ModelPoint& p = r_.hand_.points[r_.active_[a]];
      residual_[a] = std::sqrt(p.weight) / r_.config_.sigma * (PointPosition(m, d, p) - targets_[r_.active_[a]]);
    }
    const double surface_w = std::sqrt(r_.config_.contact_weight) / r_.config_.sigma;
    for (size_t i = 0; i < r_.geom_terms_.size(); ++i) {
      const GraspGap& term = r_.geom_terms_[i];
      const double d_geom = r_.surface_.GeomDistance(m, d, term.geom, &witness_[i], &normal_[i]);
      surface_residual_[i] = surface_w * (term.touch ? d_geom + r_.config_.contact_depth : std::min(0.0, d_geom));
    }
    last_.assign(x, x + n_);
    posed_ = true;
    jacobians_ = false;
  }

  // mj_jac needs mj_comPos after mj_kinematics. data_ is still posed at the
  // last Pose's x: nothing else touches it while one evaluator serves a solve.
  void Jacobians() {
    const mjModel* m = r_.hand_.model.get();
    mjData* d = r_.data_.get();
    mj_comPos(m, d);
    for (size_t a = 0; a < r_.active_.size(); ++a) {
      const ModelPoint& p = r_.hand_.points[r_.active_[a]];
      const double w = std::sqrt(p.weight) / r_.config_.sigma;
      const Vec3 x = PointPosition(m, d, p);
      mj_jac(m, d, jacp_.data(), nullptr, x.data(), p.site >= 0 ? m->site_bodyid[p.site] : p.body);
      jacobian_[a].resize(3 * n_);
      for (int row = 0; row < 3; ++row) {
        for (int f = 0; f < n_; ++f) jacobian_[a][row * n_ + f] = w * jacp_[row * m->nv + r_.dof_adr_[free_[f]]];
      }
    }
    const double surface_w = std::sqrt(r_.config_.contact_weight) / r_.config_.sigma;
    for (size_t i = 0; i < r_.geom_terms_.size(); ++i) {
      const GraspGap& term = r_.geom_terms_[i];
      surface_jacobian_[i].assign(n_, 0.0);
      if (surface_residual_[i] == 0) continue;
      mj_jac(m, d, jacp_.data(), nullptr, witness_[i].data(), m->geom_bodyid[term.geom]);
      for (int f = 0; f < n_; ++f) {
        double g = 0;
        for (int row = 0; row < 3; ++row) g += normal_[i][row] * jacp_[row * m->nv + r_.dof_adr_[free_[f]]];
        surface_jacobian_[i][f] = surface_w * g;
      }
    }
    jacobians_ = true;
  }

  KinematicRetargeter& r_;
  const std::vector<Vec3>& targets_;
  Eigen::VectorXd q_;       // all variables; the free ones from the last Pose
  std::vector<int> free_;   // indices into q_ the solver varies
  int n_;
  std::vector<mjtNum> jacp_;
  std::vector<Vec3> residual_;
  std::vector<std::vector<double>> jacobian_;
  std::vector<double> surface_residual_;
  std::vector<std::vector<double>> surface_jacobian_;
  std::vector<Vec3> witness_, normal_;  // per grasp term: nearest point and normal (GeomDistance)
  std::vector<double> last_;
  bool posed_ = false, jacobians_ = false;
};

double KinematicRetargeter::Objective(const Eigen::VectorXd& q, const std::vector<Vec3>& targets,
                                      const Eigen::VectorXd* previous, Eigen::VectorXd* residual,
                                      Eigen::MatrixXd* jacobian) {
  std::vector<int> all(q.size());
  std::iota(all.begin(), all.end(), 0);
  PointEvaluator evaluator(*this, targets, q, std::move(all));
  return evaluator.Stack(q, previous, residual, jacobian);
}

namespace {

// One residual block of a matched point: `size` residuals from `evaluate`.
class PointCost : public ceres::CostFunction {
 public:
  PointCost(std::function<void(const double*, double*, double*)> evaluate, int size, int n)
      : evaluate_(std::move(evaluate)) {
    set_num_residuals(size);
    mutable_parameter_block_sizes()->push_back(n);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    evaluate_(parameters[0], residuals, jacobians ? jacobians[0] : nullptr);
    return true;
  }

 private:
  std::function<void(const double*, double*, double*)> evaluate_;
};

// sqrt(lambda) (q - previous): the smoothness term, over all variables;
// its Jacobian has the columns of the free ones (`free`, indices into q).
class SmoothCost : public ceres::CostFunction {
 public:
  SmoothCost(const Eigen::VectorXd& q, const Eigen::VectorXd& previous, double weight, std::vector<int> free)
      : q_(q), previous_(previous), w_(weight), free_(std::move(free)) {
    set_num_residuals(static_cast<int>(previous.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(free_.size()));
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const int n = static_cast<int>(previous_.size()), nf = static_cast<int>(free_.size());
    for (int f = 0; f < nf; ++f) q_[free_[f]] = parameters[0][f];
    for (int k = 0; k < n; ++k) residuals[k] = w_ * (q_[k] - previous_[k]);
    if (jacobians && jacobians[0]) {
      std::fill(jacobians[0], jacobians[0] + n * nf, 0.0);
      for (int f = 0; f < nf; ++f) jacobians[0][free_[f] * nf + f] = w_;
    }
    return true;
  }

 private:
  mutable Eigen::VectorXd q_;  // held variables stay; the free ones from the last Evaluate
  Eigen::VectorXd previous_;
  double w_;
  std::vector<int> free_;
};

}  // namespace

// Ceres trust-region Levenberg-Marquardt: one residual block per matched
// point, under a Huber loss when robust_loss_scale > 0 (a keypoint far off,
// e.g. a mis-detected finger, then pulls linearly, not quadratically), the
// smoothness block without one, and the joint limits as parameter bounds.
// Ceres projects a step that leaves the bounds back onto them, which stalls
// the other joints when a finger rests on a limit it is pushed against, so
// this is an active-set loop: joints at a limit that the gradient pushes
// outward are held constant (left out of the parameter block) and the rest solved again,
// until the held set no longer changes. The returned objective is the plain
// least-squares one (Objective), so starts compare as before.
Eigen::VectorXd KinematicRetargeter::Minimise(Eigen::VectorXd q, const std::vector<Vec3>& targets,
                                              const Eigen::VectorXd* previous, double* objective) {
  Clamp(q);
  // The first active set from the start: a warm start at the previous
  // frame's answer begins with the joints that rested on a limit there (and
  // are still pushed), which saves the solve that would find them again.
  std::vector<int> held = PushedAgainstLimits(q, targets, previous);
  if (static_cast<int>(held.size()) == q.size()) held.clear();
  for (int round = 0; round < kActiveSetRounds; ++round) {
    SolveHolding(q, targets, previous, held);
    std::vector<int> pushed = PushedAgainstLimits(q, targets, previous);
    if (pushed == held || static_cast<int>(pushed.size()) == q.size()) break;
    held = std::move(pushed);
  }
  if (objective) *objective = Objective(q, targets, previous, nullptr, nullptr);
  return q;
}

std::vector<int> KinematicRetargeter::PushedAgainstLimits(const Eigen::VectorXd& q,
                                                          const std::vector<Vec3>& targets,
                                                          const Eigen::VectorXd* previous) {
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  Objective(q, targets, previous, &r, &J);
  const Eigen::VectorXd g = J.transpose() * r;
  std::vector<int> out;
  for (int k = 0; k < q.size(); ++k) {
    if ((q[k] <= lower_[k] + 1e-12 && g[k] > 0) || (q[k] >= upper_[k] - 1e-12 && g[k] < 0)) {
      out.push_back(k);
    }
  }
  return out;
}

void KinematicRetargeter::SolveHolding(Eigen::VectorXd& q, const std::vector<Vec3>& targets,
                                       const Eigen::VectorXd* previous,
                                       const std::vector<int>& held) {
  // The solver's parameter block is the free variables alone (held ones
  // stay at q): no Jacobian columns or manifold products for held joints.
  std::vector<int> free;
  for (int k = 0; k < static_cast<int>(q.size()); ++k) {
    if (std::find(held.begin(), held.end(), k) == held.end()) free.push_back(k);
  }
  const int n = static_cast<int>(free.size());
  if (n == 0) return;
  Eigen::VectorXd x(n);
  for (int f = 0; f < n; ++f) x[f] = q[free[f]];
  PointEvaluator evaluator(*this, targets, q, free);
  ceres::HuberLoss huber(config_.robust_loss_scale > 0 ? config_.robust_loss_scale : 1.0);
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (int i = 0; i < static_cast<int>(active_.size()); ++i) {
    PointEvaluator* e = &evaluator;
    problem.AddResidualBlock(
        new PointCost([e, i](const double* v, double* r, double* j) { e->Evaluate(v, i, r, j); }, 3, n),
        config_.robust_loss_scale > 0 ? &huber : nullptr, x.data());
  }
  for (int i = 0; i < static_cast<int>(geom_terms_.size()); ++i) {
    PointEvaluator* e = &evaluator;
    problem.AddResidualBlock(
        new PointCost([e, i](const double* v, double* r, double* j) { e->EvaluateSurface(v, i, r, j); }, 1, n),
        nullptr, x.data());
  }
  if (previous) {
    problem.AddResidualBlock(new SmoothCost(q, *previous, std::sqrt(config_.smooth_weight), free), nullptr,
                             x.data());
  }
  for (int f = 0; f < n; ++f) {
    if (std::isfinite(lower_[free[f]])) problem.SetParameterLowerBound(x.data(), f, lower_[free[f]]);
    if (std::isfinite(upper_[free[f]])) problem.SetParameterUpperBound(x.data(), f, upper_[free[f]]);
  }
  ceres::Solver::Options options;
  // The normal equations of ~30 variables: Cholesky of J'J costs less than
  // QR of J (2x less linear-solver time on Shadow, same fingertip errors).
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  // Ceres' projected line search for bounded problems evaluates Jacobians
  // at every trial step (Ceres' own comment calls it "not terribly
  // effective"); off, Shadow needs 3.2x fewer Jacobians, same errors.
  options.max_num_line_search_step_size_iterations = 0;
  options.max_num_iterations = config_.max_iterations;
  options.function_tolerance = config_.tolerance;
  options.parameter_tolerance = config_.tolerance;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  for (int f = 0; f < n; ++f) q[free[f]] = x[f];
  ReportStageProgress();
}

Eigen::VectorXd KinematicRetargeter::KabschStart(const std::vector<Vec3>& targets) const {
  const mjModel* m = hand_.model.get();
  std::vector<Vec3> goal;
  for (int i : palm_points_) goal.push_back(targets[i]);
  const Pose fit = FitRigid(palm_at_zero_, goal);
  Eigen::VectorXd q(qpos_adr_.size());
  q.head<3>() = fit.t;
  q.segment<3>(3) = EulerXYZ(fit.R());
  for (size_t k = 6; k < qpos_adr_.size(); ++k) q[k] = m->qpos0[qpos_adr_[k]];
  return q;
}

FrameSolution KinematicRetargeter::SolveFrame(const Keypoints21& human,
                                              const Eigen::VectorXd* previous, int restarts) {
  if (restarts < 0) restarts = config_.restarts;
  const std::vector<Vec3> targets = Targets(human);
  const Eigen::VectorXd kabsch = KabschStart(targets);
  FrameSolution best;
  best.objective = kInf;
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int s = 0; s <= restarts; ++s) {
    Eigen::VectorXd start;
    if (s == 0) {
      start = previous ? *previous : kabsch;
    } else {
      start = kabsch;
      const Vec3 axis(gauss(rng_), gauss(rng_), gauss(rng_));
      const double angle = config_.wrist_noise_rad * gauss(rng_);
      const Mat3 r = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix() *
                     (Eigen::AngleAxisd(kabsch[3], Vec3::UnitX()) *
                      Eigen::AngleAxisd(kabsch[4], Vec3::UnitY()) *
                      Eigen::AngleAxisd(kabsch[5], Vec3::UnitZ())).toRotationMatrix();
      start.segment<3>(3) = EulerXYZ(r);
      for (int a = 0; a < 3; ++a) start[a] += config_.wrist_noise_m * gauss(rng_);
      for (int k = 6; k < start.size(); ++k) {
        const double lo = std::isfinite(lower_[k]) ? lower_[k] : start[k] - 0.5;
        const double hi = std::isfinite(upper_[k]) ? upper_[k] : start[k] + 0.5;
        start[k] = lo + (hi - lo) * unit(rng_);
      }
    }
    double objective = 0;
    Eigen::VectorXd q = Minimise(start, targets, previous, &objective);
    if (objective < best.objective) {
      best.objective = objective;
      best.qpos = q;
      best.best_start = s;
    }
  }
  const std::vector<Vec3> x = Points(best.qpos);
  int tips = 0;
  for (size_t i = 0; i < hand_.points.size(); ++i) {
    if (!hand_.points[i].fingertip) continue;
    const double e = (x[i] - targets[i]).norm();
    best.fingertip_mean += e;
    best.fingertip_max = std::max(best.fingertip_max, e);
    ++tips;
  }
  if (tips) best.fingertip_mean /= tips;
  return best;
}

int KinematicRetargeter::PoseObject(const Keypoints21& human, const Pose& object) {
  geom_terms_.clear();
  if (config_.contact_weight <= 0 || surface_.empty() || object_qpos_ < 0) return 0;
  const mjModel* m = hand_.model.get();
  mjData* d = data_.get();
  mjtNum* q = d->qpos + object_qpos_;
  for (int a = 0; a < 3; ++a) q[a] = object.t[a];
  const Quat r = object.q.normalized();
  q[3] = r.w(), q[4] = r.x(), q[5] = r.y(), q[6] = r.z();
  mj_kinematics(m, d);
  std::vector<int> touching;
  for (size_t a = 0; a < active_.size(); ++a) {
    const int keypoint = hand_.points[active_[a]].keypoint;
    if (tip_geom_[a] >= 0 && ObjectDistance(human.row(keypoint).transpose()) < config_.contact_epsilon) {
      touching.push_back(tip_geom_[a]);
    }
  }
  if (static_cast<int>(touching.size()) < kMinGraspFingertips) touching.clear();
  for (int g : hand_geoms_) {
    geom_terms_.push_back({g, std::find(touching.begin(), touching.end(), g) != touching.end(), 0});
  }
  return static_cast<int>(touching.size());
}

double KinematicRetargeter::ObjectDistance(const Vec3& p) const {
  if (surface_.empty()) return std::numeric_limits<double>::infinity();
  return surface_.SignedDistance(data_.get(), p);
}

std::vector<KinematicRetargeter::GraspGap> KinematicRetargeter::GraspGaps(const Eigen::VectorXd& qpos) {
  Points(qpos);  // poses the hand in data_
  std::vector<GraspGap> out = geom_terms_;
  for (GraspGap& g : out) g.distance = surface_.GeomDistance(hand_.model.get(), data_.get(), g.geom);
  return out;
}

HandTrajectory KinematicRetargeter::Solve(const std::vector<Keypoints21>& human,
                                          const std::vector<bool>& valid, double fps,
                                          const std::function<void(std::size_t)>& progress,
                                          const std::vector<Pose>* object,
                                          std::vector<int>* contacts) {
  if (object && object->size() != human.size()) {
    throw Error("bad_reference", "hand and object differ in length", {.field = "object_poses"});
  }
  if (contacts) contacts->assign(human.size(), 0);
  auto is_valid = [&](size_t t) { return valid.empty() || valid[t]; };
  if (config_.scale <= 0 && hand_.embodiment.scale <= 0) {
    std::vector<Keypoints21> seen;
    for (size_t t = 0; t < human.size(); ++t) {
      if (is_valid(t)) seen.push_back(human[t]);
    }
    AdaptScale(seen);
  }
  HandTrajectory out;
  out.embodiment = hand_.embodiment.name;
  out.fps = fps;
  out.scale = scale_;
  out.qpos_names = VariableNames();
  out.qpos.resize(human.size());
  out.valid.resize(human.size());
  out.fingertip_error.assign(human.size(), std::nan(""));
  out.reference_keypoints.assign(human.size(), Keypoints21::Constant(std::nan("")));
  std::optional<Eigen::VectorXd> previous;
  Keypoints21 last_solved;
  restart_frames_.clear();
  for (size_t t = 0; t < human.size(); ++t) {
    if (progress && t > 0) progress(t);
    out.valid[t] = is_valid(t);
    if (!out.valid[t]) {
      if (previous) out.qpos[t] = *previous;
      continue;
    }
    out.reference_keypoints[t] = Reference(human[t]);
    if (object) {
      const int touching = PoseObject(human[t], (*object)[t]);
      if (contacts) (*contacts)[t] = touching;
    }
    const bool jump = !previous || (human[t] - last_solved).rowwise().norm().maxCoeff() > config_.jump_distance;
    if (jump) restart_frames_.push_back(t);
    FrameSolution s = SolveFrame(human[t], previous ? &*previous : nullptr, jump ? -1 : 0);
    last_solved = human[t];
    out.qpos[t] = s.qpos;
    out.fingertip_error[t] = s.fingertip_mean;
    if (!previous) {
      for (size_t k = 0; k < t; ++k) out.qpos[k] = s.qpos;  // leading unseen frames
    }
    previous = s.qpos;
  }
  geom_terms_.clear();
  if (!previous) {
    throw Error("bad_keypoints", "no frame with a valid hand", {.field = "valid"});
  }
  if (progress) progress(human.size());
  return out;
}

}  // namespace doasido::retarget
