// Inverse kinematics of the UR3e flange (ur3e.h) with Ceres: least squares
// over the six joint angles, bounded by the joint limits,
//   min |p(q) - p*|^2 + rot_scale^2 |R(q) - R*|_F^2 / 2,
// with automatic derivatives of the DH product. |R - R*|_F / sqrt(2) =
// 2 sin(theta / 2) ~ theta, so rot_scale is the length (m) one radian of
// orientation error is worth. The solve starts from the seed (the previous
// frame's answer, which gives continuity); if that does not converge to
// the tolerances it restarts from random configurations and keeps the
// first answer that converges. Angles are finally moved by multiples
// of 2 pi, within the limits, to the representation nearest the seed, so a
// trajectory never spins a wrist a full turn between frames.
#pragma once

#include <random>

#include "core/config.h"
#include "deploy/ur3e.h"

namespace doasido::deploy {

struct IkConfig {
  double position_tolerance = 1e-3;  // m
  double rotation_tolerance = 0.01;  // rad
  double rot_scale = 0.1;            // m per rad in the objective
  int restarts = 32;                 // random starts after a failed warm start
  int max_iterations = 200;          // Ceres iterations per start
  unsigned seed = 0;                 // random starts
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(IkConfig, position_tolerance, rotation_tolerance,
                                                rot_scale, restarts, max_iterations, seed)
void CheckConfig(const IkConfig& c, const std::string& section);

struct IkResult {
  ArmQ q = ArmQ::Zero();
  double position_error = 0;  // m
  double rotation_error = 0;  // rad
  bool reached = false;       // both errors within tolerance
  int starts = 0;             // starts tried (1 = the seed sufficed)
};

class ArmIk {
 public:
  explicit ArmIk(IkConfig config = {}, DhParameters dh = {}, ArmLimits limits = Ur3eLimits());

  // Flange pose `target` in the arm's base frame, from `seed`.
  IkResult Solve(const Pose& target, const ArmQ& seed);
  // One start only, no restarts (used by the placement search's cheap pass).
  IkResult SolveFrom(const Pose& target, const ArmQ& start);

  const ArmLimits& limits() const { return limits_; }
  const IkConfig& config() const { return config_; }

 private:
  ArmQ Nearest(ArmQ q, const ArmQ& seed) const;
  ArmQ RandomQ();

  IkConfig config_;
  DhParameters dh_;
  ArmLimits limits_;
  std::mt19937 rng_;
};

}  // namespace doasido::deploy
