// Step 1 of deploy/plan.h: where the arm stands relative to the
// trajectory. Candidates are a grid over yaw and table offsets around the
// workspace's default; each is scored on a subsample of the trajectory's
// frames (IK warm-started along them, the arm starting at home):
//   1. reach: more frames within the IK tolerances wins;
//   2. then cost = slowdown x (1 + max(0, floor - w) / floor), where the
//      slowdown is time_scaling.h's re-timing of the subsampled joint path
//      (how much slower than the video the arm must move there) and w the
//      least Manipulability (ur3e.h) over the subsample: a placement that
//      passes near a singularity costs up to twice its slowdown;
//   3. ties: smaller summed IK error, then the earlier (default-nearer)
//      candidate.
#pragma once

#include <vector>

#include "deploy/plan.h"

namespace doasido::deploy {

// `wrists` are the trajectory's frames at `fps`, in its world. The best
// candidate, and all of them best first (MakePlan tries runner-ups when
// the best one's plan leaves the wrist path between frames).
Placement SearchPlacement(const std::vector<Pose>& wrists, double fps, const PlanConfig& config);
std::vector<Placement> RankPlacements(const std::vector<Pose>& wrists, double fps, const PlanConfig& config);

}  // namespace doasido::deploy
