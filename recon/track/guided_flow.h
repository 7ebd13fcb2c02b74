// Guided Euler sampling of a flow-matching object model, seed §3.1 eq. 1.
// Each Euler step takes the model's free update of each block and blends it
// toward that block's target interpolant:
//
//   x_t = (1 - alpha) (x_{t-D} + D v(x_{t-D}, t-D | frame)) + alpha z_ref(t)
//   z_ref(t) = (1 - t) eps + t x_bar
//
// per block: the shape block with alpha_s toward the anchor frame's shape,
// the pose block with alpha_p toward the previous frame's pose; eps is the
// block's own starting noise, D = 1 / steps. alpha = 0 is the model's plain
// Euler sampler; alpha = 1 returns x_bar at t = 1.
#pragma once

#include <cstdint>
#include <string>

#include "core/config.h"
#include "core/task_pool.h"
#include "recon/track/velocity_field.h"

namespace doasido::recon {

struct GuidedFlowConfig {
  int candidates = 25;           // N per frame (seed appendix)
  int steps = 25;                // T Euler steps (seed appendix)
  double shape_guidance = 0.95;  // alpha_s; the seed: any value in [0.9, 1]
  std::uint64_t seed = 0;
  // Threads over a frame's candidates (models with ConcurrentRows, blocks
  // of 8 rows; clustering's silhouettes); the tracks do not depend on it.
  // Worth raising for an in-process model that takes more than about a
  // tenth of a millisecond per call: the Gaussian-mixture stand-in takes
  // microseconds, and waking threads 50 times a frame costs more.
  int threads = 1;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(GuidedFlowConfig, candidates, steps,
                                                shape_guidance, seed, threads)

// Throws Error("bad_config") naming section.key for a value out of range.
void CheckConfig(const GuidedFlowConfig& c, const std::string& section);

struct GuidedTargets {
  Eigen::VectorXd shape;          // x_bar of the shape block (Layout().shape_dim)
  Eigen::VectorXd pose;           // x_bar of the pose block (kPoseDim)
  double shape_guidance = 0.95;   // alpha_s
  double pose_guidance = 0.5;     // alpha_p of this frame
};

// `candidates` states (rows) for `frame`, deterministic for (seed, frame)
// and the same with or without `pool` (which splits the rows over its
// threads when the model has ConcurrentRows). Throws Error("bad_model")
// when the targets do not fit the model's layout.
StateMatrix SampleGuided(VelocityField& model, int frame, const GuidedTargets& targets,
                         int candidates, int steps, std::uint64_t seed, TaskPool* pool = nullptr);

// log p(x_pose | x_shape, frame) of every row of `x` (states at t = 1) by the
// instantaneous change of variables: `steps` Euler steps backward to t = 0
// with the model's own velocity give the pre-image x_0, and
//   log p_1(x_1) = log N(x_0,pose; 0, I) - integral_0^1 tr(dv_pose/dx_pose) dt
// (the seed's eq. writes the integral with the opposite orientation of
// time). Every step costs one Velocity and one PoseDivergence call.
Eigen::VectorXd PoseLogLikelihood(VelocityField& model, int frame, const StateMatrix& x,
                                  int steps, TaskPool* pool = nullptr);

}  // namespace doasido::recon
