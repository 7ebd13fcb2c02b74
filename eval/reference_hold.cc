#include "eval/reference_hold.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "retarget/dynamic/dynamic_reference.h"

namespace doasido::retarget {

void PoseHandAndObject(const mjModel* m, mjData* d, const HandTrajectory& traj, int k,
                       const Pose& object) {
  const SceneIndex index = IndexScene(m);
  mj_resetData(m, d);
  for (size_t i = 0; i < traj.qpos_names.size(); ++i) {
    const int joint = mj_name2id(m, mjOBJ_JOINT, traj.qpos_names[i].c_str());
    if (joint < 0) {
      throw Error("bad_mjcf", "the trajectory's joint '" + traj.qpos_names[i] + "' is not in the model",
                  {.field = "qpos_names"});
    }
    d->qpos[m->jnt_qposadr[joint]] = traj.qpos[k][i];
  }
  double* o = d->qpos + index.object_qpos;
  o[0] = object.t.x(), o[1] = object.t.y(), o[2] = object.t.z();
  o[3] = object.q.w(), o[4] = object.q.x(), o[5] = object.q.y(), o[6] = object.q.z();
}

double ReferenceHoldDrop(const mjModel* m, mjData* d, const HandTrajectory& traj, int k,
                         const Pose& object, double seconds, double settle_seconds) {
  const SceneIndex index = IndexScene(m);
  PoseHandAndObject(m, d, traj, k, object);
  for (int a = 0; a < m->nu; ++a) d->ctrl[a] = d->qpos[index.act_qpos[a]];
  double* o = d->qpos + index.object_qpos;
  const std::vector<double> held(o, o + 7);
  const int settle = static_cast<int>(std::lround(settle_seconds / m->opt.timestep));
  for (int s = 0; s < settle; ++s) {
    mj_step(m, d);
    std::copy(held.begin(), held.end(), o);
    std::fill(d->qvel + index.object_dof, d->qvel + index.object_dof + 6, 0.0);
  }
  const int steps = static_cast<int>(std::lround(seconds / m->opt.timestep));
  for (int s = 0; s < steps; ++s) mj_step(m, d);
  return object.t.z() - o[2];
}

}  // namespace doasido::retarget
