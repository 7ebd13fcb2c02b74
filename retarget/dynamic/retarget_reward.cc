#include "retarget/dynamic/retarget_reward.h"

#include <cmath>

#include "core/config_check.h"

namespace doasido::retarget {

void CheckConfig(const RewardConfig& c, const std::string& section) {
  RequireInRange(section, "pos_rew_scale", c.pos_rew_scale, 0, 1e6);
  RequireInRange(section, "rot_rew_scale", c.rot_rew_scale, 0, 1e6);
  RequireInRange(section, "base_pos_rew_scale", c.base_pos_rew_scale, 0, 1e6);
  RequireInRange(section, "base_rot_rew_scale", c.base_rot_rew_scale, 0, 1e6);
  RequireInRange(section, "joint_rew_scale", c.joint_rew_scale, 0, 1e6);
  RequireInRange(section, "terminal_rew_scale", c.terminal_rew_scale, 0, 1e6);
  RequireInRange(section, "penetration_penalty_scale", c.penetration_penalty_scale, 0, 1e9);
  RequireInRange(section, "penetration_tolerance", c.penetration_tolerance, 0, 0.1);
  RequireInRange(section, "transition_penalty_scale", c.transition_penalty_scale, 0, 1e6);
  RequireInRange(section, "transition_epsilon", c.transition_epsilon, 1e-4, 0.5);
  RequireInRange(section, "transition_rest_height", c.transition_rest_height, 0, 0.5);
}

Vec3 RotationError(const Quat& a, const Quat& b) {
  Quat d = a.conjugate() * b;
  if (d.w() < 0) d.coeffs() *= -1;  // the short way round
  const double s = d.vec().norm();
  if (s < 1e-12) return 2 * d.vec();
  return d.vec() * (2 * std::atan2(s, d.w()) / s);
}

double StepReward(const mjModel* m, const mjData* d, const SceneIndex& index,
                  const DynamicReference& ref, int step, const RewardConfig& config,
                  RewardTerms* terms) {
  const double* q = d->qpos + index.object_qpos;
  const Vec3 pos_err = Vec3(q[0], q[1], q[2]) - ref.object_pos[step];
  const Vec3 rot_err = RotationError(ref.object_quat[step], Quat(q[3], q[4], q[5], q[6]));
  double sq = config.pos_rew_scale * config.pos_rew_scale * pos_err.squaredNorm() +
              config.rot_rew_scale * config.rot_rew_scale * rot_err.squaredNorm();
  const double w[3] = {config.base_pos_rew_scale, config.base_rot_rew_scale, config.joint_rew_scale};
  const double* r = ref.ctrl.row(step).data();
  if (terms) {
    terms->object_pos_sq = config.pos_rew_scale * config.pos_rew_scale * pos_err.squaredNorm();
    terms->object_rot_sq = config.rot_rew_scale * config.rot_rew_scale * rot_err.squaredNorm();
  }
  for (int a = 0; a < m->nu; ++a) {
    const double e = w[index.act_kind[a]] * (d->qpos[index.act_qpos[a]] - r[a]);
    sq += e * e;
    if (terms) {
      const int kind = index.act_kind[a];
      (kind == kBasePos ? terms->wrist_pos_sq : kind == kBaseRot ? terms->wrist_rot_sq : terms->fingers_sq) += e * e;
    }
  }
  double reward = -std::sqrt(sq);
  if (!config.penetration && !config.transition && !terms) return reward;
  double depth = 0;
  bool floor_contact = false;
  unsigned touching = 0;  // bit h: hand h touches the object
  for (int c = 0; c < d->ncon; ++c) {
    const mjContact& con = d->contact[c];
    const int b1 = m->geom_bodyid[con.geom1], b2 = m->geom_bodyid[con.geom2];
    const bool o1 = b1 == index.object_body, o2 = b2 == index.object_body;
    const bool f = con.geom1 == index.floor_geom || con.geom2 == index.floor_geom;
    if ((o1 || o2) && f) floor_contact = true;
    if (o1 != o2 && !f) {
      const int hand = index.body_hand[o1 ? b2 : b1];
      if (hand >= 0) touching |= 1u << hand;
    }
    if (!(o1 && o2)) depth += std::max(0.0, -con.dist - config.penetration_tolerance);
  }
  if (terms) terms->penetration_depth = depth;
  if (config.penetration) reward -= config.penetration_penalty_scale * depth;
  // Resting stages: the object must touch the floor; in-hand stages: every
  // hand that holds the object in the reference must touch it.
  const bool missed = ref.resting[step] ? !floor_contact : (ref.in_hand[step] & ~touching) != 0;
  if (terms) terms->stage_missed = missed;
  if (config.transition && missed) {
    reward -= config.transition_penalty_scale;
  }
  return reward;
}

}  // namespace doasido::retarget
