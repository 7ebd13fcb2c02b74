// Two arms, two hands (the seed's bimanual setup: two UR3e arms, each with
// a hand, commanded at 50 Hz): a left and a right robot hand trajectory in
// one world become one plan for two arms whose bases stand `base_distance`
// apart, checked for arm-arm collisions, and streamed as one LCM message
// per tick.
//
// Placement: the bases stand on the table side by side, facing +x of a
// common frame, the left arm at y = +base_distance / 2 and the right at
// -base_distance / 2. The common frame is placed like one arm's base in
// plan.h (offset from the workspace config, around the mean of both
// wrists), turned so that the mean line from the right wrist to the left
// one points along its +y (then by the workspace's yaw); the one-arm search
// is not run, but a spot that fails a check is moved over the workspace's
// offset grid (MakeBimanualPlan). Both arms then go through plan.h's steps
// 2-4 on one clock (MakePlansOnOneClock): one time map re-times both paths
// so that no joint of either arm exceeds its limits, and both lead moves
// last as long as the longer one, so the two arms' commands stay in step.
//
// Collision check: every command of the re-timed plans (lead moves
// included), each arm is its six link capsules
// (ur3e.h: from each joint's origin to the next, with the links' radii)
// plus the hand as a capsule of `hand_radius` along the flange's z axis for
// `hand_length`; the least distance between a capsule of one arm and one of
// the other, surfaces to surfaces, must stay above `clearance`. On the
// path itself the two hands' envelopes are not checked against each
// other: two hands holding one object come closer than two 9-cm capsules
// allow (carries measured 1.3 cm), and the retargeting simulated both
// hands in one scene with their real geometry, so how near they come is
// the task's; the lead moves, which no simulation saw, check them too. Frames where
// it does not are listed with their times; the plan is ok only without
// them and with both arms' plans ok.
#pragma once

#include <atomic>
#include <filesystem>
#include <string>
#include <vector>

#include "deploy/plan.h"
#include "deploy/stream.h"

namespace doasido::deploy {

struct BimanualConfig {
  double base_distance = 0.6;  // m between the two bases
  double clearance = 0.02;     // m the arms (and hands) keep from each other
  // The hand's envelope: a capsule along the flange's z axis (the fingers'
  // direction); a Sharpa-sized hand is ~17 cm from wrist to fingertip and
  // 9 cm across.
  double hand_length = 0.17;   // m
  double hand_radius = 0.045;  // m
  PlanConfig plan;             // rate, IK, workspace (x, y, yaw, base height) of the pair
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(BimanualConfig, base_distance, clearance, hand_length,
                                                hand_radius, plan)
void CheckConfig(const BimanualConfig& c, const std::string& section);

struct BimanualPlan {
  Plan left, right;                  // same command times
  std::vector<FrameIssue> collisions;  // value: distance (m), limit: clearance
  std::vector<double> arm_distance;    // per command frame, m (surfaces; negative: overlapping)
  bool ok = false;
};

// Makes both plans and checks them. Trajectories must have the same frame
// rate and length (one clip). Throws Error("bad_trajectory") otherwise.
// When the pair's default spot (the workspace's x, y) fails a check, the
// pair's frame is moved over the workspace's offset grid (offset_range,
// offset_steps, as one arm's placement search) and the spot with the
// fewest failing commands, then the least slowdown, is kept (a carry whose
// forearms cross within the clearance where the hands meet, for one);
// both placements' `candidates` count the spots tried. A spot where an
// arm's joint path cannot be re-timed within time_scaling.max_slowdown
// (frames far out of reach) is passed over; when every spot is, throws
// Error(kUnfollowablePath) naming the arm, its frames and the default
// spot's placement (plan.h MakePlansOnOneClock).
BimanualPlan MakeBimanualPlan(const retarget::HandTrajectory& left, const retarget::HandTrajectory& right,
                              const retarget::Embodiment& left_hand, const retarget::Embodiment& right_hand,
                              const BimanualConfig& config);

// The least surface distance between the two arms (and hands) at joint
// angles `left`, `right` with bases `left_base`, `right_base` (base->world).
// Without `hand_to_hand`, the pair of the two hands' envelopes is left out
// (each hand against the other arm's links still counts).
double ArmArmDistance(const ArmQ& left, const Pose& left_base, const ArmQ& right, const Pose& right_base,
                      const BimanualConfig& config, bool hand_to_hand = true);

// Both arms (and hands) of `plan` in one MuJoCo scene with the object, on
// the plan's one clock (bimanual_replay.cc): each arm servoed along its
// commands as the one-arm replay does (plan.h step 5), each hand's
// actuators driven by the two-hand trajectory `both` (its variables
// prefixed kLeftPrefix / kRightPrefix) at each command's trajectory time,
// the object free. Fills plan.left.replay and plan.right.replay: each
// arm's wrist tracking, fingers and hand-object contacts, and in both the
// one object's error against the trajectory's object (the floating
// two-hand simulation's) and the trajectory's own success.
// ReplayMount::kFloating replays the retargeting's two floating hands
// under the same time map instead: the yardstick for what the re-timing
// alone does. Nothing is filled when the trajectory has no object poses
// or the scene no free "object" body.
void ReplayBimanualPlan(BimanualPlan& plan, const retarget::HandTrajectory& both,
                        const retarget::Embodiment& left_hand, const retarget::Embodiment& right_hand,
                        const std::string& scene_xml, const std::filesystem::path& scene_dir,
                        double servo_omega = PlanConfig{}.servo_omega, ReplayMount mount = ReplayMount::kArm);

// Streams doasido_lcm::bimanual_command (deploy/bimanual_command.lcm), one
// message per tick carrying both arms and both hands, as StreamPlan does
// for one arm (real-time pacing, or a dry-run log). Throws
// Error("plan_failed_checks") for a plan that is not ok.
StreamResult StreamBimanualPlan(const BimanualPlan& plan, const StreamOptions& options,
                                const std::atomic<bool>& stop);

// JSON: {"format": "doasido_bimanual_plan", "version": 1, "base_distance",
// "clearance", "left": <plan.h plan>, "right": <plan>, "arm_distance": [...],
// "collisions": [{frame, time, distance}], "ok"}. Throws Error("io") /
// Error("bad_plan") naming the file and field.
inline constexpr const char* kBimanualPlanFormat = "doasido_bimanual_plan";
void WriteBimanualPlanJson(const BimanualPlan& plan, const BimanualConfig& config,
                           const std::filesystem::path& path);
BimanualPlan BimanualPlanFromJson(const Json& j, const std::string& file);

struct BimanualRecord {
  int64_t log_time_us = 0, timestamp_us = 0, sequence = 0;
  double plan_time = 0;
  ArmQ left_arm = ArmQ::Zero(), right_arm = ArmQ::Zero();
  std::vector<double> left_hand, right_hand;
};
// Every bimanual_command on `channel` in an LCM log. Throws Error("bad_log").
std::vector<BimanualRecord> ReadBimanualLog(const std::filesystem::path& path,
                                            const std::string& channel = kCommandChannel);

}  // namespace doasido::deploy
