// A tiny but complete retargeting configuration for tests: every component
// on, a handful of samples, the shared robots (retarget_dynamics_test,
// retarget_grasp_test).
#pragma once

#include "retarget/dynamic/dynamic_retarget.h"
#include "tests/test_util.h"

namespace doasido::testing {

inline retarget::DynamicRetargetConfig SmallRetargetConfig(int threads = 2) {
  retarget::DynamicRetargetConfig c;
  c.preset = "";
  c.robots_dir = (SharedData() / "robots").string();
  c.kinematic.restarts = 1;
  retarget::AnnealedSamplerConfig& s = c.sampler;
  s.num_samples = 8;
  s.max_num_iterations = 2;
  s.horizon = 0.2;
  s.knot_dt = 0.1;
  s.ctrl_dt = 0.1;
  s.warmup_seconds = 0.1;
  s.num_perturb_samples = 2;
  s.threads = threads;
  s.seed = 3;
  return c;
}

}  // namespace doasido::testing
