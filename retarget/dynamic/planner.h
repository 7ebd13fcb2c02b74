// The receding-horizon planner behind RetargetDynamics (annealed_sampler.h;
// internal to retarget/dynamic/): per plan, samples control knots around
// the nominal, rolls them out on the thread pool, weights them by return
// and shifts the horizon along the reference.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "retarget/dynamic/annealed_sampler.h"
#include "retarget/dynamic/rollout_pool.h"

namespace doasido::retarget {

// The part of mjData a step depends on. Copying it (not the whole arena)
// restarts a rollout exactly, whichever thread's data ran before.
struct RolloutState {
  double time = 0;
  std::vector<double> qpos, qvel, act, warm;
};

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

  DynamicResult Run(const std::function<void(int, int)>& progress, const WindowTraceFn& trace = {});

 private:
  // The nominal control of actuator a at `step` (feed-forward targets).
  double RefCtrl(int step, int a) const {
    return ref_.feedforward(std::clamp(step, 0, ref_.steps() - 1), a);
  }
  void Clamp(double* u) const {
    for (int a = 0; a < m_->nu; ++a) u[a] = std::clamp(u[a], index_.ctrl_lo[a], index_.ctrl_hi[a]);
  }
  void HoldObject(mjData* d, int step) const;
  // Simulates `knots` from state_ over `length` steps from `start`:
  // the return; perturbation sequence `perturbation` of `key` when
  // perturbing (< 0: none); `outcome`, when set, gets the object's final
  // height and the return's parts (PlanOutcome).
  double Rollout(const double* knots, int perturbation, int thread, int start, int length,
                 std::uint64_t key, PlanOutcome* outcome = nullptr);
  // Adds one step's reward parts, weighted as the return weighs it.
  void AddTerms(const RewardTerms& terms, double weight, PlanOutcome& outcome) const;
  const double* Sample(int c) const { return buffer_.data() + static_cast<size_t>(c) * knots_ * m_->nu; }
  // The reference's feed-forward controls as knots of the window at
  // `start` (clamped): the first nominal, and a plan the trace scores.
  void ReferenceKnots(int start, RowMatrix& out) const;
  // For the trace: the state's finger gap and hand-object contacts.
  void DescribeState(const mjData* d, int step, WindowTrace& w) const;
  // After Optimise: the executed plan, the weighted mean or the best sample.
  void KeepTheBetterPlan(int start, int length, std::uint64_t key);
  // Rolls the window's plans out for `trace` (WindowTrace).
  void Trace(const mjData* d, int start, int plan, int iterations, const RowMatrix& entering,
             const WindowTraceFn& trace);
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
  int best_ = 0;                        // the best sample of the last iteration
  std::vector<double> buffer_;          // (samples, knots, nu)
  std::vector<double> rollout_return_;  // (samples * group)
  std::vector<double> returns_, weights_;
  RowMatrix nominal_, sigma_;           // (knots, nu)
  RolloutState state_;
  double weight_ = 0;
  SamplerStats stats_;
};

}  // namespace doasido::retarget
