#include "retarget/dynamic/planner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/error.h"
#include "core/stage_progress.h"
#include "retarget/dynamic/sampler_rng.h"

namespace doasido::retarget {
namespace {

using Clock = std::chrono::steady_clock;

// The warning count Load sets (see there): any other count after a step
// means MuJoCo met a non-finite state.
constexpr int kNoBadState = 1 << 20;

void Save(const mjModel* m, const mjData* d, RolloutState& s) {
  s.time = d->time;
  s.qpos.assign(d->qpos, d->qpos + m->nq);
  s.qvel.assign(d->qvel, d->qvel + m->nv);
  s.act.assign(d->act, d->act + m->na);
  s.warm.assign(d->qacc_warmstart, d->qacc_warmstart + m->nv);
}

void Load(const mjModel* m, const RolloutState& s, mjData* d) {
  d->time = s.time;
  std::copy(s.qpos.begin(), s.qpos.end(), d->qpos);
  std::copy(s.qvel.begin(), s.qvel.end(), d->qvel);
  std::copy(s.act.begin(), s.act.end(), d->act);
  std::copy(s.warm.begin(), s.warm.end(), d->qacc_warmstart);
  std::fill(d->xfrc_applied, d->xfrc_applied + 6 * m->nbody, 0.0);
  std::fill(d->qfrc_applied, d->qfrc_applied + m->nv, 0.0);
  // MuJoCo reacts to a non-finite state by printing a warning (only while
  // its count is 0), resetting the data (count 0) and counting it (1). A
  // sentinel count therefore silences the print and still shows the event.
  for (int w : {mjWARN_BADQACC, mjWARN_BADQPOS, mjWARN_BADQVEL}) d->warning[w].number = kNoBadState;
}

bool BadState(const mjData* d) {
  return d->warning[mjWARN_BADQACC].number != kNoBadState ||
         d->warning[mjWARN_BADQPOS].number != kNoBadState ||
         d->warning[mjWARN_BADQVEL].number != kNoBadState;
}

// Uniform direction, size uniform in [0, scale]: three values into `out`.
void RandomWrench(Rng& rng, double scale, double* out) {
  Vec3 dir(rng.Normal(), rng.Normal(), rng.Normal());
  dir /= std::max(dir.norm(), 1e-12);
  const double size = scale * rng.Uniform();
  for (int i = 0; i < 3; ++i) out[i] = size * dir[i];
}

}  // namespace

void Planner::HoldObject(mjData* d, int step) const {
  if (step >= ref_.warmup_steps) return;
  double* q = d->qpos + index_.object_qpos;
  const Vec3& p = ref_.object_pos[0];
  const Quat& r = ref_.object_quat[0];
  q[0] = p.x(), q[1] = p.y(), q[2] = p.z(), q[3] = r.w(), q[4] = r.x(), q[5] = r.y(), q[6] = r.z();
  std::fill(d->qvel + index_.object_dof, d->qvel + index_.object_dof + 6, 0.0);
}

void Planner::ReferenceKnots(int start, RowMatrix& out) const {
  out.resize(knots_, m_->nu);
  for (int k = 0; k < knots_; ++k) {
    const int step = start + static_cast<int>(std::lround(k * c_.knot_dt / ref_.dt));
    for (int a = 0; a < m_->nu; ++a) out(k, a) = RefCtrl(step, a);
    Clamp(out.row(k).data());
  }
}

void Planner::DescribeState(const mjData* d, int step, WindowTrace& w) const {
  int fingers = 0;
  for (int a = 0; a < m_->nu; ++a) {
    if (index_.act_kind[a] != kFinger) continue;
    w.finger_gap += std::abs(d->qpos[index_.act_qpos[a]] - ref_.ctrl(step, a));
    ++fingers;
  }
  w.finger_gap /= std::max(1, fingers);
  for (int c = 0; c < d->ncon; ++c) {
    const mjContact& con = d->contact[c];
    const int b1 = m_->geom_bodyid[con.geom1], b2 = m_->geom_bodyid[con.geom2];
    if ((b1 == index_.object_body) == (b2 == index_.object_body)) continue;
    if (index_.body_hand[b1 == index_.object_body ? b2 : b1] < 0) continue;
    mjtNum f[6];
    mj_contactForce(m_, d, c, f);
    ++w.object_contacts;
    w.object_force += f[0];
  }
}

double Planner::Rollout(const double* knots, int perturbation, int thread, int start, int length,
                        std::uint64_t key, PlanOutcome* outcome) {
  mjData* d = pool_.data(thread);
  Load(m_, state_, d);
  // Common random numbers: perturbation k of every control sample draws
  // the same stream.
  Rng rng{Mix(key, static_cast<std::uint64_t>(std::max(0, perturbation)), 0x5eed, 1)};
  double* xfrc = d->xfrc_applied + 6 * index_.object_body;
  bool active = false;
  double total = 0;
  for (int h = 0; h < length; ++h) {
    EvaluateKnots(knots, knots_, m_->nu, c_.knot_dt, h * ref_.dt, d->ctrl);
    if (perturbation >= 0) {
      const bool was = active;
      active = gate_[start + h] && rng.Uniform() < (was ? c_.perturb_continue_prob : c_.perturb_prob);
      if (active && !was) {
        RandomWrench(rng, c_.perturb_force_scale * weight_, xfrc);
        RandomWrench(rng, c_.perturb_torque_scale * weight_ * 0.05, xfrc + 3);
      } else if (!active) {
        std::fill(xfrc, xfrc + 6, 0.0);
      }
    }
    mj_step(m_, d);
    const int s = start + h + 1;
    HoldObject(d, s);
    if (BadState(d)) return -std::numeric_limits<double>::infinity();
    RewardTerms terms;
    const double r = StepReward(m_, d, index_, ref_, s, c_.reward, outcome ? &terms : nullptr);
    const double weight = h == length - 1 ? c_.reward.terminal_rew_scale : 1.0;
    total += weight * r;
    if (outcome) AddTerms(terms, weight, *outcome);
  }
  const double weights = length - 1 + c_.reward.terminal_rew_scale;
  if (outcome) {
    outcome->object_z = d->qpos[index_.object_qpos + 2];
    for (double* part : {&outcome->object_pos, &outcome->object_rot, &outcome->wrist_pos, &outcome->wrist_rot,
                         &outcome->fingers, &outcome->penetration, &outcome->transition}) {
      *part /= weights;
    }
  }
  return total / weights;
}

void Planner::AddTerms(const RewardTerms& t, double weight, PlanOutcome& o) const {
  o.object_pos += weight * std::sqrt(t.object_pos_sq);
  o.object_rot += weight * std::sqrt(t.object_rot_sq);
  o.wrist_pos += weight * std::sqrt(t.wrist_pos_sq);
  o.wrist_rot += weight * std::sqrt(t.wrist_rot_sq);
  o.fingers += weight * std::sqrt(t.fingers_sq);
  if (c_.reward.penetration) o.penetration += weight * c_.reward.penetration_penalty_scale * t.penetration_depth;
  if (c_.reward.transition && t.stage_missed) o.transition += weight * c_.reward.transition_penalty_scale;
}

int Planner::Optimise(int start, int plan) {
  const int nu = m_->nu, length = std::min(horizon_steps_, ref_.steps() - 1 - start);
  const bool perturb = std::any_of(gate_.begin() + start, gate_.begin() + start + length,
                                   [](uint8_t g) { return g != 0; });
  group_ = perturb ? std::max(1, c_.num_perturb_samples) : 1;
  samples_ = std::max(2, c_.num_samples / group_);
  returns_.resize(samples_);  // within the capacity reserved: no allocation
  weights_.resize(samples_);
  const double beta = std::pow(c_.final_noise_scale, 1.0 / c_.max_num_iterations);
  int it = 0;
  while (it < c_.max_num_iterations) {
    DrawSamples(nominal_, sigma_, std::pow(beta, it), Mix(c_.seed, plan, it, 0xa11), index_.ctrl_lo,
                index_.ctrl_hi, samples_, buffer_);
    const std::uint64_t key = Mix(c_.seed, plan, it, 0xf0);
    const auto t0 = Clock::now();
    pool_.Run(samples_ * group_, [&](int n, int thread) {
      rollout_return_[n] = Rollout(Sample(n / group_), group_ > 1 ? n % group_ : -1, thread, start, length, key);
    });
    stats_.rollout_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    stats_.rollouts += samples_ * group_;
    ReportStageProgress();
    stats_.sim_steps += static_cast<long long>(samples_) * group_ * length;
    double worst = 0;
    for (int n = 0; n < samples_ * group_; ++n) {
      if (std::isfinite(rollout_return_[n])) worst = std::min(worst, rollout_return_[n]);
    }
    for (int c = 0; c < samples_; ++c) {  // failed rollouts score as the worst (SPIDER)
      double sum = 0;
      for (int g = 0; g < group_; ++g) {
        const double r = rollout_return_[c * group_ + g];
        sum += std::isfinite(r) ? r : worst - 1;
      }
      returns_[c] = sum / group_;
    }
    WeightSamples(returns_, c_.top_fraction, c_.temperature, weights_);
    nominal_.setZero();
    for (int c = 0; c < samples_; ++c) {
      if (weights_[c] == 0) continue;
      nominal_ += weights_[c] * Eigen::Map<const RowMatrix>(
                                    buffer_.data() + static_cast<size_t>(c) * knots_ * nu, knots_, nu);
    }
    ++it;
    best_ = static_cast<int>(std::max_element(returns_.begin(), returns_.end()) - returns_.begin());
    if (returns_[best_] - returns_[0] < c_.improvement_threshold) break;
  }
  stats_.iterations += it;
  KeepTheBetterPlan(start, length, Mix(c_.seed, plan, it - 1, 0xf0));
  return it;
}

// The weighted mean of the top samples was never simulated: a mean of
// controls that each hold the object need not hold it (issue 51: the mean
// of samples no better than the nominal opened the grip). It is rolled out
// under the last iteration's perturbations and replaced by the best sample
// when that scored higher (MuJoCo MPC's sampling planner keeps its best).
void Planner::KeepTheBetterPlan(int start, int length, std::uint64_t key) {
  pool_.Run(group_, [&](int g, int thread) {
    rollout_return_[g] = Rollout(nominal_.data(), group_ > 1 ? g : -1, thread, start, length, key);
  });
  stats_.rollouts += group_;
  stats_.sim_steps += static_cast<long long>(group_) * length;
  double mean = 0;
  for (int g = 0; g < group_; ++g) {
    mean += std::isfinite(rollout_return_[g]) ? rollout_return_[g] : -std::numeric_limits<double>::infinity();
  }
  mean /= group_;
  if (returns_[best_] > mean) nominal_ = Eigen::Map<const RowMatrix>(Sample(best_), knots_, m_->nu);
}

void Planner::Shift(int start, int next_start) {
  const int nu = m_->nu;
  const RowMatrix old = nominal_;
  const double shift = (next_start - start) * ref_.dt;
  const double old_end = (knots_ - 1) * c_.knot_dt;
  const int end_step = start + static_cast<int>(std::lround(old_end / ref_.dt));
  for (int k = 0; k < knots_; ++k) {
    const double t = shift + k * c_.knot_dt;
    double* u = nominal_.row(k).data();
    if (t <= old_end + 1e-9) {
      EvaluateKnots(old.data(), knots_, nu, c_.knot_dt, t, u);
    } else {
      const double alpha = c_.blend_seconds > 0 ? std::min(1.0, (t - old_end) / c_.blend_seconds) : 1.0;
      const int s = start + static_cast<int>(std::lround(t / ref_.dt));
      for (int a = 0; a < nu; ++a) {
        u[a] = RefCtrl(s, a) + (1 - alpha) * (old(knots_ - 1, a) - RefCtrl(end_step, a));
      }
    }
    Clamp(u);
  }
}

void Planner::Trace(const mjData* d, int start, int plan, int iterations, const RowMatrix& entering,
                    const WindowTraceFn& trace) {
  const int length = std::min(horizon_steps_, ref_.steps() - 1 - start);
  WindowTrace w;
  w.plan = plan;
  w.time = (start - ref_.warmup_steps) * ref_.dt;
  w.end_time = (start + length - ref_.warmup_steps) * ref_.dt;
  w.ref_object_z = ref_.object_pos[start + length].z();
  w.iterations = iterations;
  w.best_score = returns_[best_];
  DescribeState(d, start, w);
  RowMatrix reference;
  ReferenceKnots(start, reference);
  const auto outcome = [&](const double* knots) {
    PlanOutcome o;
    o.ret = Rollout(knots, -1, 0, start, length, 0, &o);
    return o;
  };
  w.nominal = outcome(entering.data());
  w.reference = outcome(reference.data());
  w.best = outcome(Sample(best_));
  w.executed = outcome(nominal_.data());
  trace(w);
}

DynamicResult Planner::Run(const std::function<void(int, int)>& progress, const WindowTraceFn& trace) {
  const auto t0 = Clock::now();
  const int steps = ref_.steps(), nu = m_->nu;
  DataPtr d = MakeData(m_);
  mj_resetData(m_, d.get());
  for (int a = 0; a < nu; ++a) d->qpos[index_.act_qpos[a]] = ref_.ctrl(0, a);
  {
    double* q = d->qpos + index_.object_qpos;
    const Vec3& p = ref_.object_pos[0];
    const Quat& r = ref_.object_quat[0];
    q[0] = p.x(), q[1] = p.y(), q[2] = p.z(), q[3] = r.w(), q[4] = r.x(), q[5] = r.y(), q[6] = r.z();
  }
  mj_forward(m_, d.get());
  DynamicResult out;
  out.qpos.resize(steps, m_->nq);
  out.ctrl.resize(steps, nu);
  out.qpos.row(0) = Eigen::Map<const Eigen::RowVectorXd>(d->qpos, m_->nq);
  out.ctrl.row(0) = ref_.ctrl.row(0);
  ReferenceKnots(0, nominal_);
  const int ctrl_steps = std::max(1, static_cast<int>(std::lround(c_.ctrl_dt / ref_.dt)));
  for (int start = 0, plan = 0; start < steps - 1; start += ctrl_steps, ++plan) {
    Save(m_, d.get(), state_);
    const RowMatrix entering = trace ? nominal_ : RowMatrix();
    const int iterations = Optimise(start, plan);
    ++stats_.plans;
    if (trace) Trace(d.get(), start, plan, iterations, entering, trace);
    Load(m_, state_, d.get());
    const int run = std::min(ctrl_steps, steps - 1 - start);
    for (int h = 0; h < run; ++h) {
      EvaluateKnots(nominal_.data(), knots_, nu, c_.knot_dt, h * ref_.dt, d->ctrl);
      mj_step(m_, d.get());
      const int s = start + h + 1;
      HoldObject(d.get(), s);
      if (BadState(d.get()) || !Eigen::Map<const Eigen::VectorXd>(d->qpos, m_->nq).allFinite()) {
        throw Error("unstable_simulation",
                    "non-finite state at step " + std::to_string(s) + " (t = " +
                        std::to_string((s - ref_.warmup_steps) * ref_.dt) + " s)",
                    {.field = "qpos"});
      }
      out.qpos.row(s) = Eigen::Map<const Eigen::RowVectorXd>(d->qpos, m_->nq);
      out.ctrl.row(s) = Eigen::Map<const Eigen::RowVectorXd>(d->ctrl, nu);
    }
    Shift(start, start + ctrl_steps);
    if (progress) progress(start + run, steps - 1);
  }
  stats_.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  out.stats = stats_;
  return out;
}

}  // namespace doasido::retarget
