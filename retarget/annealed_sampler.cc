#include "retarget/annealed_sampler.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/config_check.h"
#include "core/error.h"
#include "core/stage_progress.h"
#include "retarget/rollout_pool.h"

namespace doasido::retarget {
namespace {

using Clock = std::chrono::steady_clock;

// SplitMix64: a tiny generator whose stream is the same on every platform
// and costs nothing to seed per rollout.
struct Rng {
  std::uint64_t s;
  std::uint64_t Next() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double Uniform() { return (Next() >> 11) * (1.0 / 9007199254740992.0); }
  double Normal() {  // Box-Muller
    const double u = std::max(Uniform(), 1e-300), v = Uniform();
    return std::sqrt(-2 * std::log(u)) * std::cos(2 * M_PI * v);
  }
};

std::uint64_t Mix(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d) {
  Rng r{a * 0x100000001b3ULL ^ (b << 40) ^ (c << 20) ^ d};
  return r.Next();
}

// The part of mjData a step depends on. Copying it (not the whole arena)
// restarts a rollout exactly, whichever thread's data ran before.
constexpr int kNoBadState = 1 << 20;

struct State {
  double time = 0;
  std::vector<double> qpos, qvel, act, warm;
};

void Save(const mjModel* m, const mjData* d, State& s) {
  s.time = d->time;
  s.qpos.assign(d->qpos, d->qpos + m->nq);
  s.qvel.assign(d->qvel, d->qvel + m->nv);
  s.act.assign(d->act, d->act + m->na);
  s.warm.assign(d->qacc_warmstart, d->qacc_warmstart + m->nv);
}

void Load(const mjModel* m, const State& s, mjData* d) {
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

class Planner {
 public:
  Planner(const mjModel* m, const DynamicReference& ref, const AnnealedSamplerConfig& config)
      : m_(m), ref_(ref), c_(config), index_(IndexScene(m)), pool_(m, config.threads),
        knots_(KnotCount(config.horizon, config.knot_dt)),
        horizon_steps_(static_cast<int>(std::lround(config.horizon / ref.dt))),
        gate_(PerturbationGate(ref, config)), nominal_(knots_, m->nu), sigma_(knots_, m->nu) {
    const int most = std::max(2, config.num_samples);
    buffer_.resize(static_cast<size_t>(most) * knots_ * m->nu);
    rollout_return_.resize(std::max(most, 2 * std::max(1, config.num_perturb_samples)));
    returns_.reserve(most);
    weights_.reserve(most);
    const double mass = m->body_subtreemass[index_.object_body];
    weight_ = mass * std::abs(m->opt.gravity[2]);
    sigma_ = NoiseScales(c_, index_.act_kind, knots_);
  }

  DynamicResult Run(const std::function<void(int, int)>& progress);

 private:
  // The nominal control of actuator a at `step` (feed-forward targets).
  double RefCtrl(int step, int a) const {
    return ref_.feedforward(std::clamp(step, 0, ref_.steps() - 1), a);
  }
  void Clamp(double* u) const {
    for (int a = 0; a < m_->nu; ++a) u[a] = std::clamp(u[a], index_.ctrl_lo[a], index_.ctrl_hi[a]);
  }
  void HoldObject(mjData* d, int step) const;
  double Rollout(int rollout, int thread, int start, int length, std::uint64_t key);
  int Optimise(int start, int plan);
  void Shift(int start, int next_start);

  const mjModel* m_;
  const DynamicReference& ref_;
  AnnealedSamplerConfig c_;
  SceneIndex index_;
  RolloutPool pool_;
  int knots_, horizon_steps_;
  std::vector<uint8_t> gate_;           // (steps) perturbations allowed
  int group_ = 1, samples_ = 2;         // of the current plan
  std::vector<double> buffer_;          // (samples, knots, nu)
  std::vector<double> rollout_return_;  // (samples * group)
  std::vector<double> returns_, weights_;
  RowMatrix nominal_, sigma_;           // (knots, nu)
  State state_;
  double weight_ = 0;
  SamplerStats stats_;
};

void Planner::HoldObject(mjData* d, int step) const {
  if (step >= ref_.warmup_steps) return;
  double* q = d->qpos + index_.object_qpos;
  const Vec3& p = ref_.object_pos[0];
  const Quat& r = ref_.object_quat[0];
  q[0] = p.x(), q[1] = p.y(), q[2] = p.z(), q[3] = r.w(), q[4] = r.x(), q[5] = r.y(), q[6] = r.z();
  std::fill(d->qvel + index_.object_dof, d->qvel + index_.object_dof + 6, 0.0);
}

double Planner::Rollout(int rollout, int thread, int start, int length, std::uint64_t key) {
  mjData* d = pool_.data(thread);
  Load(m_, state_, d);
  const double* knots = buffer_.data() + static_cast<size_t>(rollout / group_) * knots_ * m_->nu;
  // Common random numbers: perturbation k of every control sample draws
  // the same stream.
  Rng rng{Mix(key, static_cast<std::uint64_t>(rollout % group_), 0x5eed, 1)};
  double* xfrc = d->xfrc_applied + 6 * index_.object_body;
  bool active = false;
  double total = 0;
  for (int h = 0; h < length; ++h) {
    EvaluateKnots(knots, knots_, m_->nu, c_.knot_dt, h * ref_.dt, d->ctrl);
    if (group_ > 1) {
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
    const double r = StepReward(m_, d, index_, ref_, s, c_.reward);
    total += (h == length - 1 ? c_.reward.terminal_rew_scale : 1.0) * r;
  }
  return total / (length - 1 + c_.reward.terminal_rew_scale);
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
      rollout_return_[n] = Rollout(n, thread, start, length, key);
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
    const double best = *std::max_element(returns_.begin(), returns_.end());
    if (best - returns_[0] < c_.improvement_threshold) break;
  }
  stats_.iterations += it;
  return it;
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

DynamicResult Planner::Run(const std::function<void(int, int)>& progress) {
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
  for (int k = 0; k < knots_; ++k) {
    for (int a = 0; a < nu; ++a) {
      nominal_(k, a) = RefCtrl(static_cast<int>(std::lround(k * c_.knot_dt / ref_.dt)), a);
    }
    Clamp(nominal_.row(k).data());
  }
  const int ctrl_steps = std::max(1, static_cast<int>(std::lround(c_.ctrl_dt / ref_.dt)));
  for (int start = 0, plan = 0; start < steps - 1; start += ctrl_steps, ++plan) {
    Save(m_, d.get(), state_);
    Optimise(start, plan);
    ++stats_.plans;
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

}  // namespace

std::vector<uint8_t> PerturbationGate(const DynamicReference& ref, const AnnealedSamplerConfig& c) {
  const int steps = ref.steps(), lag = static_cast<int>(std::lround(c.perturb_gate_seconds / ref.dt));
  std::vector<uint8_t> gate(steps, 0);
  if (!c.perturb) return gate;
  for (int s = ref.warmup_steps + lag; s + lag < steps; ++s) {
    bool held = true;
    for (int k = s - lag; k <= s + lag && held; ++k) held = ref.in_hand[k] != 0;
    gate[s] = held;
  }
  return gate;
}

void CheckConfig(const AnnealedSamplerConfig& c, const std::string& section) {
  RequireInRange(section, "num_samples", c.num_samples, 2, 1 << 20);
  RequireInRange(section, "max_num_iterations", c.max_num_iterations, 1, 10000);
  RequireInRange(section, "ctrl_dt", c.ctrl_dt, 1e-3, 100);
  RequireInRange(section, "horizon", c.horizon, c.ctrl_dt, 100);
  RequireInRange(section, "knot_dt", c.knot_dt, 1e-3, c.horizon);
  RequireInRange(section, "pos_noise_scale", c.pos_noise_scale, 0, 1);
  RequireInRange(section, "rot_noise_scale", c.rot_noise_scale, 0, 3.2);
  RequireInRange(section, "joint_noise_scale", c.joint_noise_scale, 0, 3.2);
  RequireInRange(section, "final_noise_scale", c.final_noise_scale, 1e-6, 1);
  RequireInRange(section, "first_ctrl_noise_scale", c.first_ctrl_noise_scale, 1e-6, 1e3);
  RequireInRange(section, "last_ctrl_noise_scale", c.last_ctrl_noise_scale, 1e-6, 1e3);
  RequireInRange(section, "top_fraction", c.top_fraction, 1e-6, 1);
  RequireInRange(section, "temperature", c.temperature, 1e-6, 1e6);
  RequireInRange(section, "improvement_threshold", c.improvement_threshold, 0, 1e6);
  RequireInRange(section, "blend_seconds", c.blend_seconds, 0, 100);
  RequireInRange(section, "warmup_seconds", c.warmup_seconds, -1, 100);
  RequireInRange(section, "num_perturb_samples", c.num_perturb_samples, 1, 1024);
  RequireInRange(section, "perturb_force_scale", c.perturb_force_scale, 0, 1e3);
  RequireInRange(section, "perturb_torque_scale", c.perturb_torque_scale, 0, 1e3);
  RequireInRange(section, "perturb_prob", c.perturb_prob, 0, 1);
  RequireInRange(section, "perturb_continue_prob", c.perturb_continue_prob, 0, 1);
  RequireInRange(section, "perturb_gate_seconds", c.perturb_gate_seconds, 0, 100);
  RequireInRange(section, "threads", c.threads, 1, 1024);
  CheckConfig(c.reward, section + ".reward");
}

AnnealedSamplerConfig SamplerPreset(const std::string& name) {
  AnnealedSamplerConfig c;
  if (name == "seed") return c;
  if (name == "fast") {
    c.num_samples = 64;
    c.max_num_iterations = 8;
    c.horizon = 1.0;
    c.knot_dt = 0.25;
    c.blend_seconds = 0.25;
    return c;
  }
  throw Error("bad_config", "unknown sampler preset '" + name + "' (seed, fast)", {.field = "preset"});
}

RowMatrix NoiseScales(const AnnealedSamplerConfig& config, const std::vector<int>& act_kind,
                      int knots) {
  const double base[3] = {config.pos_noise_scale, config.rot_noise_scale, config.joint_noise_scale};
  RowMatrix sigma(knots, act_kind.size());
  for (int k = 0; k < knots; ++k) {
    const double along = config.first_ctrl_noise_scale *
                         std::pow(config.last_ctrl_noise_scale / config.first_ctrl_noise_scale,
                                  knots > 1 ? k / double(knots - 1) : 0.0);
    for (size_t a = 0; a < act_kind.size(); ++a) sigma(k, a) = along * base[act_kind[a]];
  }
  return sigma;
}

void DrawSamples(const RowMatrix& nominal, const RowMatrix& sigma, double anneal,
                 std::uint64_t key, const std::vector<double>& lo, const std::vector<double>& hi,
                 int samples, std::vector<double>& out) {
  const int knots = static_cast<int>(nominal.rows()), nu = static_cast<int>(nominal.cols());
  out.resize(static_cast<size_t>(samples) * knots * nu);
  Rng rng{key};
  double* u = out.data();
  for (int c = 0; c < samples; ++c) {
    for (int k = 0; k < knots; ++k, u += nu) {
      for (int a = 0; a < nu; ++a) {
        const double x = nominal(k, a) + (c == 0 ? 0.0 : sigma(k, a) * anneal * rng.Normal());
        u[a] = std::clamp(x, lo[a], hi[a]);
      }
    }
  }
}

double WarmupSeconds(const AnnealedSamplerConfig& config) {
  if (!config.warmup) return 0;
  return config.warmup_seconds < 0 ? config.horizon : config.warmup_seconds;
}

void WeightSamples(const std::vector<double>& returns, double top_fraction, double temperature,
                   std::vector<double>& weights) {
  const int n = static_cast<int>(returns.size());
  const int top = std::clamp(static_cast<int>(std::ceil(top_fraction * n)), 1, n);
  // The top-th largest return; ties at the threshold all count.
  std::vector<double> sorted(returns);
  std::nth_element(sorted.begin(), sorted.begin() + (top - 1), sorted.end(), std::greater<>());
  const double threshold = sorted[top - 1];
  double mean = 0, var = 0;
  int count = 0;
  for (double r : returns) {
    if (r >= threshold) mean += r, ++count;
  }
  mean /= count;
  for (double r : returns) {
    if (r >= threshold) var += (r - mean) * (r - mean);
  }
  const double sd = std::sqrt(var / count) + 1e-12;
  double best = -std::numeric_limits<double>::infinity();
  for (double r : returns) best = std::max(best, (r - mean) / sd / temperature);
  double sum = 0;
  weights.assign(n, 0.0);
  for (int i = 0; i < n; ++i) {
    if (returns[i] >= threshold) sum += weights[i] = std::exp((returns[i] - mean) / sd / temperature - best);
  }
  for (double& w : weights) w /= sum;
}

DynamicResult RetargetDynamics(const mjModel* m, const DynamicReference& ref,
                               const AnnealedSamplerConfig& config,
                               const std::function<void(int, int)>& progress) {
  if (ref.steps() < 2) throw Error("bad_reference", "reference shorter than two steps");
  Planner planner(m, ref, config);
  return planner.Run(progress);
}

}  // namespace doasido::retarget
