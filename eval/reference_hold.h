// Whether a reference grasp can hold its object at all: the hand stands at
// one frame of a kinematic reference with its actuators targeting that pose,
// the object starts where the reference has it, and the simulation runs.
// A reference whose own grasp drops the object cannot be tracked into a
// lift by any sampler (retarget_dynamics_bench --sections=grasp,
// retarget_grasp_test).
#pragma once

#include <mujoco/mujoco.h>

#include "core/geometry.h"
#include "retarget/kinematic/kinematic_retarget.h"

namespace doasido::retarget {

// Resets `d` and sets the joints `traj` names to its frame k and the scene's
// object (SceneIndex) to `object`. Joints `traj` does not name keep qpos0.
// Throws Error("bad_mjcf") when a named joint is not in `m`.
void PoseHandAndObject(const mjModel* m, mjData* d, const HandTrajectory& traj, int k,
                       const Pose& object);

// How far (m) the object falls in `seconds` from the pose of
// PoseHandAndObject, every actuator targeting its joint's value there. The
// object is first held in place for `settle_seconds` while the hand settles
// onto it, as the seed's warmup does (a reference pressed into the surface
// would otherwise fling the object away at the first step), then let go.
double ReferenceHoldDrop(const mjModel* m, mjData* d, const HandTrajectory& traj, int k,
                         const Pose& object, double seconds, double settle_seconds = 0.3);

}  // namespace doasido::retarget
