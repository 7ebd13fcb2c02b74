// Dynamics-aware retargeting by annealed sampling (seed section 3.2 and
// appendix; SPIDER, REFERENCE.md section 5), on CPU threads.
//
// Controls are position targets for every actuator, parameterised by knots
// knot_dt apart over the horizon and linearly interpolated (knot_spline.h).
// Each planning step (every ctrl_dt of simulated time, receding horizon):
//   for iteration i < max_num_iterations:
//     sample c = 0 is the current plan, samples c > 0 add Gaussian noise with
//     per-component scale (pos / rot / joint_noise_scale), growing along the
//     horizon from first_ctrl_noise_scale to last_ctrl_noise_scale
//     (geometric), times beta^i, beta = final_noise_scale^(1/max_iterations);
//     every sample is simulated over the horizon from the current state and
//     scored by the mean step reward (retarget_reward.h), the last step
//     weighted terminal_rew_scale;
//     the top `top_fraction` returns are z-scored and soft-maxed with
//     `temperature`; the plan becomes the weighted mean of their knots;
//     stop early when best return - return of sample 0 < improvement_threshold.
//   The last weighted mean is rolled out too (under the last iteration's
//   perturbations; the samples' mean was never simulated) and replaced by
//   the last iteration's best sample when that scored higher (MuJoCo MPC
//   keeps its best likewise; issue 51: a mean of samples no better than the
//   nominal opened the grip before a lift).
//   The first ctrl_dt of the plan is executed (no perturbation) and the plan
//   shifted: knots inside the old horizon keep the optimised controls; knots
//   beyond it take the next chunk of reference with the optimised offset at
//   the old end blended linearly into the reference over blend_seconds
//   (seed "Reference Blending").
//
// Seed components, each switchable:
//  - warmup: warmup_seconds (default: the horizon) of reference frame 0 are
//    prepended; meanwhile the object is held at its frame-0 pose (its free
//    joint is reset every step, which acts as a weld to the world without
//    toggling eq_active in per-thread model copies) while the hand moves.
//  - perturbation: only while the reference holds the object off the floor
//    (DynamicReference::in_hand) for perturb_gate_seconds before and after
//    the step: a stable hold is what it tests, and a push on a resting or
//    just-released object only scatters the returns. A plan whose horizon
//    reaches such a step splits num_samples into num_samples /
//    num_perturb_samples control samples, each simulated num_perturb_samples
//    times under random forces and torques on the object, scored by the
//    mean return; the k-th perturbation sequence is the same for every
//    control sample (common random numbers), so returns differ by the
//    controls, not by the luck of the draw. A perturbation starts with
//    probability perturb_prob per step and continues with
//    perturb_continue_prob; its direction is uniform on the sphere, its size
//    uniform up to perturb_force_scale times the object's weight (torque:
//    perturb_torque_scale times weight x 5 cm). Other plans use all
//    num_samples as control samples. The rollout budget stays num_samples
//    per iteration (a GPU implementation may afford num_samples x
//    num_perturb_samples rollouts; on two cores the row would cost 4x).
//  - transition reward and penetration penalty: RewardConfig.
//
// Determinism: all noise is drawn from `seed` per (plan, iteration, sample),
// and every rollout starts from a full copy of the state (including the
// solver's warm start), so the result does not depend on the thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/config.h"
#include "retarget/dynamic/dynamic_reference.h"
#include "retarget/dynamic/retarget_reward.h"

namespace doasido::retarget {

struct AnnealedSamplerConfig {
  // Algorithm (seed table; sim_dt is the scene's timestep, 0.005).
  int num_samples = 1024;
  int max_num_iterations = 32;
  double ctrl_dt = 0.5;
  double horizon = 3.0;
  // Sampling.
  double knot_dt = 0.2;
  double pos_noise_scale = 0.01;    // m, wrist translation targets
  double rot_noise_scale = 0.01;    // rad, wrist rotation targets
  double joint_noise_scale = 0.1;   // rad, finger targets
  double final_noise_scale = 0.01;
  double first_ctrl_noise_scale = 1.0;
  double last_ctrl_noise_scale = 4.0;
  double top_fraction = 0.1;
  double temperature = 0.1;
  double improvement_threshold = 0.01;
  double blend_seconds = 0.5;
  // Components.
  bool warmup = true;
  double warmup_seconds = -1;  // < 0: the horizon
  bool perturb = true;
  int num_perturb_samples = 4;
  double perturb_force_scale = 0.5;
  double perturb_torque_scale = 0.5;
  double perturb_prob = 0.05;
  double perturb_continue_prob = 0.95;
  double perturb_gate_seconds = 0.25;  // not in the seed's table; our lifts last ~1 s
  RewardConfig reward;
  // Execution.
  int threads = 2;
  std::uint64_t seed = 0;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(
    AnnealedSamplerConfig, num_samples, max_num_iterations, ctrl_dt, horizon, knot_dt,
    pos_noise_scale, rot_noise_scale, joint_noise_scale, final_noise_scale,
    first_ctrl_noise_scale, last_ctrl_noise_scale, top_fraction, temperature,
    improvement_threshold, blend_seconds, warmup, warmup_seconds, perturb, num_perturb_samples,
    perturb_force_scale, perturb_torque_scale, perturb_prob, perturb_continue_prob,
    perturb_gate_seconds, reward, threads,
    seed)
void CheckConfig(const AnnealedSamplerConfig& c, const std::string& section);

// The named presets: "seed" (the seed's table, the defaults), "fast" (the
// project's CPU setting: 64 samples, 8 iterations, 1-s horizon) and
// "medium" (the ladder's middle rung, between the two). Throws
// Error("bad_config") for another name.
AnnealedSamplerConfig SamplerPreset(const std::string& name);

// Seconds of warmup the reference for `config` needs (BuildReference):
// 0 without warmup, else warmup_seconds, or the horizon when that is < 0.
double WarmupSeconds(const AnnealedSamplerConfig& config);

// Per knot and actuator: the noise scale at iteration 0 (pos / rot /
// joint_noise_scale by the actuator's kind, SceneIndex::act_kind, times a
// factor growing geometrically from first_ctrl_noise_scale at knot 0 to
// last_ctrl_noise_scale at the last knot). (knots, nu).
RowMatrix NoiseScales(const AnnealedSamplerConfig& config, const std::vector<int>& act_kind,
                      int knots);

// Fills `out` (samples, knots, nu) with control samples around `nominal`:
// sample 0 is `nominal` itself, sample c > 0 adds N(0, (anneal * sigma)^2)
// noise drawn from `key`; every value clamped to [lo, hi] per actuator.
void DrawSamples(const RowMatrix& nominal, const RowMatrix& sigma, double anneal,
                 std::uint64_t key, const std::vector<double>& lo, const std::vector<double>& hi,
                 int samples, std::vector<double>& out);

// Per step of `ref`: 1 where rollouts may perturb the object (see
// "perturbation" above): after warmup, with a hand holding the object off
// the floor from perturb_gate_seconds before the step to as long after.
// All 0 when `config.perturb` is off.
std::vector<uint8_t> PerturbationGate(const DynamicReference& ref, const AnnealedSamplerConfig& config);

// Softmax weights of the top `top_fraction` of `returns` (z-scored, divided
// by `temperature`); the others get 0. Writes into `weights` (same size).
void WeightSamples(const std::vector<double>& returns, double top_fraction, double temperature,
                   std::vector<double>& weights);

struct SamplerStats {
  int plans = 0;
  int iterations = 0;        // summed over plans
  long long rollouts = 0;
  long long sim_steps = 0;   // inside rollouts
  double rollout_seconds = 0;  // wall time spent in rollouts
  double seconds = 0;          // total wall time
};

struct DynamicResult {
  RowMatrix qpos;   // (steps, nq) simulated state at every step, warmup included
  RowMatrix ctrl;   // (steps, nu) executed targets
  SamplerStats stats;
};

// What one planning window did (a diagnosis for benches, issue 51): each
// plan is rolled out once more from the window's start state, without
// perturbation, over the window's horizon; per plan its return (the
// optimiser's score), the object's height at the horizon's end, and the
// return's parts: each tracking term's weighted error (the norm's
// components: object position and rotation, wrist position and rotation,
// fingers) and the two penalties, averaged with the return's step weights.
struct PlanOutcome {
  double ret = 0;
  double object_z = 0;
  double object_pos = 0, object_rot = 0, wrist_pos = 0, wrist_rot = 0, fingers = 0;
  double penetration = 0, transition = 0;
};
struct WindowTrace {
  int plan = 0;
  double time = 0;          // s from frame 0 at the window's start
  double end_time = 0;      // s from frame 0 at the horizon's end
  double ref_object_z = 0;  // the reference object's height there
  int iterations = 0;
  PlanOutcome nominal;      // the plan entering the window (sample 0 of iteration 0)
  PlanOutcome reference;    // the reference's feed-forward controls (RefCtrl)
  PlanOutcome best;         // the best sample of the last iteration
  PlanOutcome executed;     // the plan executed (the weighted mean or the best sample)
  double best_score = 0;    // the best sample's return as the optimiser scored it
  // The executed state at the window's start: mean |finger joint - reference|
  // (rad), hand-object contacts and their summed normal force (N).
  double finger_gap = 0;
  int object_contacts = 0;
  double object_force = 0;
};
using WindowTraceFn = std::function<void(const WindowTrace&)>;

// Optimises and executes the whole reference in `m` (IndexScene's layout).
// The initial state: hand joints at reference step 0, object at its
// reference pose, at rest. `progress`, when set, gets (done, total) steps;
// `trace`, when set, gets every window (costs four rollouts a window).
// Throws Error("unstable_simulation") when the executed state turns
// non-finite (MuJoCo's bad qpos/qvel/qacc warnings).
DynamicResult RetargetDynamics(const mjModel* m, const DynamicReference& ref,
                               const AnnealedSamplerConfig& config,
                               const std::function<void(int, int)>& progress = {},
                               const WindowTraceFn& trace = {});

}  // namespace doasido::retarget
