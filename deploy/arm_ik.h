// Inverse kinematics of the UR3e flange (ur3e.h) with Ceres: least squares
// over the six joint angles, bounded by the joint limits,
//   min |p(q) - p*|^2 + rot_scale^2 |R(q) - R*|_F^2 / 2,
// with automatic derivatives of the DH product. |R - R*|_F / sqrt(2) =
// 2 sin(theta / 2) ~ theta, so rot_scale is the length (m) one radian of
// orientation error is worth. The solve starts from the seed (the previous
// frame's answer, which gives continuity); if that does not converge to
// the tolerances it restarts from random configurations and keeps the
// first answer that converges. Angles are finally moved by multiples of
// 2 pi, within the limits, to the representation nearest the seed, so a
// trajectory never spins a wrist a full turn between frames.
//
// A pose a UR arm reaches has up to eight solutions (ClosedFormIk), and
// near a singularity, after a long step or past a frame out of reach the
// warm start can slide onto another one: between the two frames the arm
// would then swing through the jump while both frames are reached
// (ref4_noisy: the flange 313 mm off the wrist path). Besides the
// warm-started chain (SolveChain), LeastMotionPath chooses, frame by
// frame, among the poses' closed-form solutions the chain of least motion
// (the sum of squared joint steps, each joint's weighted by its speed
// limit: one long swing costs more than many short steps), by dynamic
// programming over the branches; where the closed form has no solution
// (out of reach) each branch goes on with its nearest answer (least
// squares from it), not a random start's. The plan (plan.h step
// 2) keeps the warm-started chain unless it strays off the wrist path
// between frames and the least-motion chain strays less.
#pragma once

#include <random>
#include <vector>

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

// The closed-form inverse kinematics of a UR arm (three parallel axes and
// an offset wrist; the derivation of Hawkins, "Analytic Inverse Kinematics
// for the Universal Robots UR-5/UR-10 Arms", 2013): the joint vectors, one
// per branch (shoulder, wrist and elbow each two ways), that put the
// flange at `target`, angles in [-pi, pi]; none when the pose is out of
// reach. At the wrist singularity (sin q5 = 0) q6 is free: `q6` is taken.
// Joint limits are not applied.
std::vector<ArmQ> ClosedFormIk(const Pose& target, double q6, const DhParameters& dh = {});

// The time a move from `a` to `b` needs at each joint's speed limit,
// summed in squares (s): how near two solutions are for the arm.
double JointDistance(const ArmQ& a, const ArmQ& b, const ArmLimits& limits);

class ArmIk {
 public:
  explicit ArmIk(IkConfig config = {}, DhParameters dh = {}, ArmLimits limits = Ur3eLimits());

  // Flange pose `target` in the arm's base frame, from `seed` (the
  // placement search's and the lead-in's solve).
  IkResult Solve(const Pose& target, const ArmQ& seed);
  // Every pose of a path, each seeded with the answer before (the first
  // with `start`): the warm-started chain.
  std::vector<IkResult> SolveChain(const std::vector<Pose>& targets, const ArmQ& start);
  // The chain of least motion over the closed-form branches (see above).
  std::vector<IkResult> LeastMotionPath(const std::vector<Pose>& targets, const ArmQ& start);
  // One start only, no restarts (used by the placement search's cheap pass).
  IkResult SolveFrom(const Pose& target, const ArmQ& start);

  const ArmLimits& limits() const { return limits_; }
  const IkConfig& config() const { return config_; }

 private:
  ArmQ Nearest(ArmQ q, const ArmQ& seed) const;
  bool WithinLimits(const ArmQ& q) const;
  // Random starts while `best` is not reached.
  void Restart(const Pose& target, const ArmQ& seed, IkResult& best, int& starts);
  IkResult Exact(const Pose& target, const ArmQ& q) const;
  ArmQ RandomQ();

  IkConfig config_;
  DhParameters dh_;
  ArmLimits limits_;
  std::mt19937 rng_;
};

}  // namespace doasido::deploy
