// The reward of one simulation step of a rollout (seed appendix table
// "Rewards"; SPIDER): tracking as the negated norm of the weighted errors
//   - || (w_pos e_obj_pos, w_rot e_obj_rot, w_base_pos e_wrist_pos,
//         w_base_rot e_wrist_rot, w_joint e_fingers) ||
// where object rotation error is the rotation vector of q_ref^-1 q, wrist
// errors are the floating-base joint differences and finger errors the
// joint differences to the kinematic reference; minus penetration_scale
// times the summed contact depth beyond `penetration_tolerance` (the object
// hulls are dilated 2 mm, so a little is expected), minus transition_scale
// when the reference's stage is not met (seed "Transition Reward"): no
// object-floor contact while resting, no hand-object contact while in hand;
// with two hands, per hand: a hand the reference has holding the object
// (DynamicReference::in_hand) that does not touch it. Stages: in hand when
// the human hand is within transition_epsilon of the object (the seed's
// rule) and the object is off the floor; resting when the object's lowest
// point is within transition_rest_height of the floor (DynamicReference).
#pragma once

#include "core/config.h"
#include "retarget/dynamic/dynamic_reference.h"

namespace doasido::retarget {

struct RewardConfig {
  double pos_rew_scale = 1.0;
  double rot_rew_scale = 0.3;
  double base_pos_rew_scale = 0.1;
  double base_rot_rew_scale = 0.03;
  double joint_rew_scale = 0.01;
  double terminal_rew_scale = 10.0;        // the horizon's last step counts this many times
  bool penetration = true;
  double penetration_penalty_scale = 3000.0;  // per metre of depth
  double penetration_tolerance = 0.002;       // m of depth not penalised
  bool transition = true;
  double transition_penalty_scale = 0.5;
  double transition_epsilon = 0.02;  // m: hand-object distance labelling "in hand"
  double transition_rest_height = 0.01;  // m: object bottom height labelling "resting"
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(RewardConfig, pos_rew_scale, rot_rew_scale,
                                                base_pos_rew_scale, base_rot_rew_scale,
                                                joint_rew_scale, terminal_rew_scale, penetration,
                                                penetration_penalty_scale, penetration_tolerance,
                                                transition, transition_penalty_scale,
                                                transition_epsilon, transition_rest_height)
void CheckConfig(const RewardConfig& c, const std::string& section);

// The parts of one step's reward, for diagnosis: the squares of the
// weighted errors under the tracking norm (object position, object
// rotation, wrist position, wrist rotation, fingers), the penetration
// depth beyond the tolerance (m) and whether the stage was missed.
struct RewardTerms {
  double object_pos_sq = 0, object_rot_sq = 0, wrist_pos_sq = 0, wrist_rot_sq = 0, fingers_sq = 0;
  double penetration_depth = 0;
  bool stage_missed = false;
};

// Reward of the state in `d` against reference step `step`. No allocation.
// `terms`, when set, gets its parts (the reward is the same either way).
double StepReward(const mjModel* m, const mjData* d, const SceneIndex& index,
                  const DynamicReference& ref, int step, const RewardConfig& config,
                  RewardTerms* terms = nullptr);

// Rotation vector (axis * angle, angle in [0, pi]) of a^-1 b.
Vec3 RotationError(const Quat& a, const Quat& b);

}  // namespace doasido::retarget
