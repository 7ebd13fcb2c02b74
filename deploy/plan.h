// `doasido deploy plan`: a robot trajectory (retarget/kinematic_retarget.h
// HandTrajectory, the floating wrist plus finger joints) becomes joint
// commands for a UR3e carrying the hand (ur3e.h), at a fixed command rate.
//
// 1. Placement. The trajectory's world has the table top (its floor) at
//    z = 0. The arm's base stands on the table; the trajectory is turned by
//    a yaw about the vertical and its mean wrist position is put at an
//    offset from the base:  p_base = Rz(yaw) (p - c) + (x, y, -base_height),
//    c = (mean wrist x, mean wrist y, 0). The workspace config gives the
//    default (x, y, yaw); a grid search over yaw and offsets around it keeps
//    the placement where inverse kinematics reaches most of a subsample of
//    frames (ties: smaller summed error, then the earlier, i.e. default-
//    nearer, candidate).
// 2. Arm IK (arm_ik.h) for the wrist pose of every command frame, warm
//    started from the previous frame; the wrist pose and finger joints are
//    interpolated from the trajectory (slerp / linear) at the command times.
// 3. Checks: frames IK does not reach within tolerance ("unreachable") and
//    frames whose joint speed from the previous command exceeds the arm's
//    speed limits ("too_fast"), each with its time; the plan is ok when
//    there are none.
// 4. Replay (when the trajectory has object poses and a scene): the arm is
//    driven kinematically along the commands (the real arm's joint servo is
//    stiff), the fingers through the hand's position actuators, and the
//    object moves freely; the object's error against the trajectory's
//    object poses is reported (position m, rotation rad; success as in
//    REFERENCE.md section 5: mean < 0.10 m and < 0.5 rad).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/config.h"
#include "core/geometry.h"
#include "deploy/arm_ik.h"
#include "deploy/ur3e.h"
#include "retarget/kinematic_retarget.h"

namespace doasido::deploy {

struct WorkspaceConfig {
  double x = 0.32;            // m, default position of the trajectory's centre from the base
  double y = 0.0;
  double yaw = 0.0;           // rad, default turn of the trajectory about the vertical
  double base_height = 0.0;   // m, arm base above the table top
  int yaw_steps = 12;         // candidates over a full turn (1 = no yaw search)
  double offset_range = 0.1;  // m, offsets searched within +- this of (x, y)
  int offset_steps = 3;       // per axis (1 = no offset search)
  int search_frames = 20;     // frames subsampled for each candidate
  int search_restarts = 2;    // IK restarts per frame in the search
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(WorkspaceConfig, x, y, yaw, base_height, yaw_steps,
                                                offset_range, offset_steps, search_frames,
                                                search_restarts)
void CheckConfig(const WorkspaceConfig& c, const std::string& section);

struct PlanConfig {
  double rate_hz = 50;  // command rate
  bool replay = true;
  WorkspaceConfig workspace;
  IkConfig ik;
  std::array<double, 6> home{0, -1.5708, 1.5708, -1.5708, -1.5708, 0};  // first IK seed, rad
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(PlanConfig, rate_hz, replay, workspace, ik, home)
void CheckConfig(const PlanConfig& c, const std::string& section);

struct Placement {
  double yaw = 0;
  double x = 0, y = 0;
  Pose world_to_base;          // p_base = world_to_base * p_world
  double reachable_fraction = 0;  // of the searched subsample
  int candidates = 0;
};

struct FrameIssue {
  int frame = 0;
  double time = 0;   // s from the trajectory's start
  double value = 0;  // unreachable: position error (m); too_fast: speed (rad/s)
  double limit = 0;  // too_fast: the joint's limit; unreachable: rotation error (rad)
  int joint = -1;    // too_fast: arm joint index
};

struct ReplayReport {
  bool ran = false;
  double object_position_error_mean = 0, object_position_error_max = 0;  // m
  double object_rotation_error_mean = 0, object_rotation_error_max = 0;  // rad
  bool success = false;
};

struct Plan {
  std::string source;      // trajectory file
  std::string embodiment;
  double rate_hz = 50;
  Placement placement;
  std::vector<std::string> arm_joints;
  std::vector<std::string> hand_joints;
  std::vector<double> times;          // s
  std::vector<ArmQ> arm;              // rad
  std::vector<Eigen::VectorXd> hand;  // the hand's joints, hand_joints order
  std::vector<double> position_error, rotation_error;  // IK residual per frame
  std::vector<FrameIssue> unreachable, too_fast;
  ReplayReport replay;
  bool ok = false;  // no unreachable and no too-fast frame
};

// The floating-wrist pose of `frame` in the trajectory's world (joints
// doasido_wrist_x..rz, rotation Rx Ry Rz). Throws Error("bad_trajectory").
Pose WristPose(const retarget::HandTrajectory& t, int frame);

// Steps 1-3 above. `scene_xml`/`scene_dir` as BuildArmHandModel; the hand
// joints are those of `embodiment`'s model, filled from the trajectory's
// qpos by name (a joint the trajectory lacks keeps 0). Throws
// Error("bad_trajectory") for an empty trajectory or one without a wrist.
// `placement` (may be null) fixes the placement instead of step 1's search.
// A fixed placement's reachable_fraction is the share of all command
// frames the IK reached, its candidates 1.
Plan MakePlan(const retarget::HandTrajectory& trajectory, const retarget::Embodiment& embodiment,
              const PlanConfig& config, const Placement* placement = nullptr);

// The placement p_base = Rz(yaw) (p - c) + (x, y, -base_height) of step 1,
// c the mean of `wrists` on the table (z = 0).
Pose PlacementPose(double yaw, double x, double y, const std::vector<Pose>& wrists, double base_height);

// Step 4 on a plan made from `trajectory`; fills plan.replay.
void ReplayPlan(Plan& plan, const retarget::HandTrajectory& trajectory,
                const retarget::Embodiment& embodiment, const std::string& scene_xml,
                const std::filesystem::path& scene_dir);

// JSON: {"format": "doasido_deploy_plan", "version": 1, "source", "embodiment",
// "rate_hz", "placement": {yaw, x, y, world_to_base: [tx,ty,tz,qw,qx,qy,qz],
// reachable_fraction, candidates}, "arm_joints", "hand_joints", "times",
// "arm": [[6]], "hand": [[n]], "position_error", "rotation_error",
// "unreachable": [{frame, time, position_error, rotation_error}],
// "too_fast": [{frame, time, joint, speed, limit}], "replay": {...}, "ok"}.
// The "format" member of a plan file.
inline constexpr const char* kPlanFormat = "doasido_deploy_plan";
void WritePlanJson(const Plan& plan, const std::filesystem::path& path);
// Throws Error("bad_plan") naming the file and field.
Plan ReadPlanJson(const std::filesystem::path& path);
// The same as JSON values (a two-arm plan holds two; bimanual.h), and a
// plan file's JSON (Error("bad_plan") when unreadable or not JSON).
Json PlanToJson(const Plan& plan);
Plan PlanFromJson(const Json& j, const std::string& file);
Json ReadPlanFile(const std::filesystem::path& path);

}  // namespace doasido::deploy
