#include "retarget/dynamic/annealed_sampler.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/config_check.h"
#include "core/error.h"
#include "retarget/dynamic/planner.h"
#include "retarget/dynamic/sampler_rng.h"

namespace doasido::retarget {

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
  if (name == "medium") {  // the ladder's middle rung: see docs/retargeting.md for the measurement
    c.num_samples = 256;
    c.max_num_iterations = 16;
    c.horizon = 1.5;
    c.knot_dt = 0.25;
    c.blend_seconds = 0.5;
    return c;
  }
  throw Error("bad_config", "unknown sampler preset '" + name + "' (seed, medium, fast)", {.field = "preset"});
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
                               const std::function<void(int, int)>& progress, const WindowTraceFn& trace) {
  if (ref.steps() < 2) throw Error("bad_reference", "reference shorter than two steps");
  Planner planner(m, ref, config);
  return planner.Run(progress, trace);
}

}  // namespace doasido::retarget
