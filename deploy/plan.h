// `doasido deploy plan`: a robot trajectory (retarget/kinematic_retarget.h
// HandTrajectory, the floating wrist plus finger joints) becomes joint
// commands for a UR3e carrying the hand (ur3e.h), at a fixed command rate,
// re-timed so that the arm can run them.
//
// 0. Smoothing (wrist_smoothing.h): a hand-only trajectory's wrist path is
//    low-passed within a tolerance (the jitter of a wrist tracked from
//    video is noise the arm need not follow); the plan follows the
//    smoothed path, the replay measures against the trajectory's own.
// 1. Placement (placement.h). The trajectory's world has the table top (its
//    floor) at z = 0. The arm's base stands on the table; the trajectory is
//    turned by a yaw about the vertical and its mean wrist position is put
//    at an offset from the base:  p_base = Rz(yaw) (p - c) + (x, y,
//    -base_height), c = (mean wrist x, mean wrist y, 0). The workspace
//    config gives the default (x, y, yaw); a grid search over yaw and
//    offsets around it keeps the placement that reaches most frames, then
//    needs the least slowdown away from singularities; when the plan there
//    fails step 4's off_path check, the next placements of the search
//    (workspace.fallback_placements) are planned too and the plan with the
//    fewest failing commands is kept.
// 2. Arm IK (arm_ik.h) for the wrist pose of every trajectory frame, warm
//    started from the previous frame (the first from home): the joint path
//    q(s), s the trajectory's time, a cubic spline through the frames.
//    Where that chain jumps between two of a pose's solutions, the flange
//    swings off the wrist path between the frames (JointSplineDeviation
//    beyond path_check's tolerances): the chain of least motion over the
//    poses' closed-form solutions (ArmIk::LeastMotionPath) is taken
//    instead when it strays less.
// 3. Time scaling (time_scaling.h): s(t) so that every joint stays within
//    its speed and acceleration limits, never faster than the video,
//    starting and ending at rest. The commands are at t = k / rate: a
//    lead-in from the home pose to a pose approach_height above the first
//    frame's wrist and down onto it (no faster than approach_speed, so a
//    clip that starts at or on the object is not swept into from the
//    side), the re-timed path (the
//    hand's joints sampled from the trajectory at the same s), a lead-out
//    back home; the lead moves are rest-to-rest quintics within the limits.
//    The plan records each command's trajectory time (the time map,
//    `source_times`) and the slowdown (re-timed duration over the
//    trajectory's).
// 4. Checks: trajectory frames IK does not reach within tolerance
//    ("unreachable", with their trajectory time) and commands whose finite
//    difference speed or acceleration exceeds a limit ("too_fast",
//    "over_acceleration", with their plan time; the arm at rest before the
//    first command and after the last). If a command exceeds a limit, step
//    3 runs again aiming at a smaller share of the limits (time_scaling
//    attempts). Then the commands between the frames ("off_path",
//    PathDeviation): the IK solved the arm only at the trajectory's
//    frames, and where its answer jumps from one solution to another
//    between two frames the arm swings through the jump while the frames
//    themselves are reached; so the flange of every command of the
//    re-timed path (forward kinematics of what the arm will receive) is
//    compared with the wrist path interpolated at the command's trajectory
//    time, and runs of commands beyond path_check's tolerances are listed
//    with the frames they lie between. The plan is ok when no frame or
//    command is listed.
// 5. Replay (replay.cc; when the trajectory has object poses and a scene):
//    the arm tracks the commands by a joint servo (PlanConfig servo_omega),
//    the fingers by the hand's position actuators
//    with the trajectory's own controls at each command's trajectory time
//    (its joint positions when it has none), the object moves freely; the
//    object's error against the trajectory's object poses at the same
//    trajectory time (position m, rotation rad; success as in REFERENCE.md
//    section 5: mean < 0.10 m and < 0.5 rad), and the wrist tracking error
//    (the simulated flange against the trajectory's wrist), the finger
//    joints' error and the hand-object contacts per command. The same
//    replay on the retargeting's floating hand (ReplayMount::kFloating,
//    its wrist driven by the trajectory's wrist controls under the same
//    time map) tells what the re-timing does from what the arm does.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/config.h"
#include "core/geometry.h"
#include "deploy/arm_ik.h"
#include "deploy/time_scaling.h"
#include "deploy/ur3e.h"
#include "deploy/wrist_smoothing.h"
#include "robot/trajectory/format.h"

namespace doasido::deploy {

struct WorkspaceConfig {
  double x = 0.32;            // m, default position of the trajectory's centre from the base
  double y = 0.0;
  double yaw = 0.0;           // rad, default turn of the trajectory about the vertical
  double base_height = 0.0;   // m, arm base above the table top
  int yaw_steps = 12;         // candidates over a full turn (1 = no yaw search)
  double offset_range = 0.1;  // m, offsets searched within +- this of (x, y)
  int offset_steps = 3;       // per axis (1 = no offset search)
  int search_frames = 40;     // frames subsampled for each candidate
  int search_restarts = 2;    // IK restarts per frame in the search
  // Manipulability (ur3e.h, 0..1) below which a placement's cost grows
  // (placement.h); 0 ignores singularities.
  double manipulability_floor = 0.05;
  // Runner-up placements planned when the best one's plan leaves the
  // wrist path between frames (step 4's off_path; MakePlan).
  int fallback_placements = 3;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(WorkspaceConfig, x, y, yaw, base_height, yaw_steps,
                                                offset_range, offset_steps, search_frames,
                                                search_restarts, manipulability_floor, fallback_placements)
void CheckConfig(const WorkspaceConfig& c, const std::string& section);

// Step 4's between-frames check (PathDeviation): how far the flange of a
// commanded joint vector may stray from the wrist path, interpolated
// between the trajectory's frames (positions linearly, rotations by slerp)
// at the command's trajectory time. A clean plan strays a few millimetres
// at most (the joint spline between IK solutions against a straight line
// between wrist poses); an IK branch jump swings the flange tens of
// centimetres off.
// The config file's section of PlanConfig (and its tables, e.g.
// [deploy.path_check]), and the field prefix of its errors.
inline constexpr const char* kPlanConfigSection = "deploy";

struct PathCheckConfig {
  double position_tolerance = 0.01;  // m
  double rotation_tolerance = 0.1;   // rad
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(PathCheckConfig, position_tolerance, rotation_tolerance)
void CheckConfig(const PathCheckConfig& c, const std::string& section);

struct PlanConfig {
  double rate_hz = 50;  // command rate
  bool replay = true;
  WorkspaceConfig workspace;
  IkConfig ik;
  TimeScalingConfig time_scaling;
  // The arm's home pose (rad): the first IK seed, where the lead-in starts
  // and the lead-out ends.
  std::array<double, 6> home{0, -1.5708, 1.5708, -1.5708, -1.5708, 0};
  bool lead_in = true;   // move from home to the first frame
  bool lead_out = true;  // and back home after the last
  // The lead-in ends coming down onto the first frame from this height
  // above it (m; 0: straight from home), at most at approach_speed (m/s).
  double approach_height = 0.05;
  double approach_speed = 0.05;
  // The replay's arm servo (rad/s): each arm joint tracks its command by a
  // computed-torque PD, M (w^2 e + 2 w e') + bias, critically damped at
  // this natural frequency; 40 is the floating wrist's servo in the
  // retargeting (retarget/embodiment.h), so the hand meets the object as
  // stiffly as it did there. 0 drives the arm kinematically (infinitely stiff).
  double servo_omega = 40;
  // Step 3b: plan the arm on the wrist path the floating hand followed
  // when replayed under the last plan's time map (needs the scene; see
  // PlanOnFloatingWrist), this many rounds (0: on the trajectory's wrist,
  // recorded at the video's clock). A second round replays under the time
  // map of the path that will run (it kept ref0_noisy, which one lost).
  int follow_rounds = 2;
  // s: the window of the moving average over the followed wrist's offset
  // from the trajectory's (FloatingWristTrajectory).
  double follow_smoothing = 0.2;
  // Step 0 (wrist_smoothing.h): the wrist path low-passed before planning.
  WristSmoothingConfig wrist_smoothing;
  // Step 4's check of the commands between the frames.
  PathCheckConfig path_check;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(PlanConfig, rate_hz, replay, workspace, ik, time_scaling,
                                                home, lead_in, lead_out, approach_height, approach_speed,
                                                servo_omega, follow_rounds, follow_smoothing, wrist_smoothing,
                                                path_check)
void CheckConfig(const PlanConfig& c, const std::string& section);

struct Placement {
  double yaw = 0;
  double x = 0, y = 0;
  Pose world_to_base;          // p_base = world_to_base * p_world
  double reachable_fraction = 0;  // of the searched subsample
  int candidates = 0;
  double search_slowdown = 0;  // the search's estimate of the slowdown (placement.h)
  double manipulability = 0;   // the least over the searched frames
};

// unreachable: frame = trajectory frame, time = its trajectory time;
// too_fast / over_acceleration: frame = command, time = plan time.
struct FrameIssue {
  int frame = 0;
  double time = 0;   // s
  double value = 0;  // unreachable: position error (m); too_fast: speed (rad/s); over_acceleration: rad/s^2
  double limit = 0;  // too_fast, over_acceleration: the joint's limit; unreachable: rotation error (rad)
  int joint = -1;    // too_fast, over_acceleration: arm joint index
};

// The error of a joint path the re-timing gives up on
// (TimeScalingConfig::max_slowdown): MakePlansOnOneClock names the arm,
// the frames and the placement.
inline constexpr const char* kUnfollowablePath = "unfollowable_path";

// The names of step 4's checks: the plan file's lists and what `deploy
// plan` prints.
inline constexpr const char* kCheckUnreachable = "unreachable";
inline constexpr const char* kCheckTooFast = "too_fast";
inline constexpr const char* kCheckOverAcceleration = "over_acceleration";
inline constexpr const char* kCheckOffPath = "off_path";

// A run of path commands whose flange strays beyond the path check's
// tolerance (either of them) from the wrist path; runs only apart where
// the joint spline passes through a frame's IK answer (back on the path
// for an instant) are one.
struct OffPathSpan {
  int first_command = 0, last_command = 0;  // plan commands, inclusive
  int commands = 0;                         // of them, beyond the tolerance
  double start_time = 0, end_time = 0;      // s, their plan times
  int from_frame = 0, to_frame = 0;         // the trajectory frames the run lies between
  double position_deviation = 0;            // m, the largest in the run
  double rotation_deviation = 0;            // rad
  // rad: the largest change of one joint of the IK's answer from one frame
  // to the next within [from_frame, to_frame]: the branch jump, if any.
  double joint_jump = 0;
};

// Step 4's between-frames check over the path's commands (the lead moves
// have no wrist target).
struct PathDeviation {
  bool checked = false;     // false: a plan file from before the check
  double position_max = 0;  // m, over every path command
  double rotation_max = 0;  // rad
  int worst_command = -1;   // the command of position_max
  double position_tolerance = 0, rotation_tolerance = 0;  // the config's, recorded
  std::vector<OffPathSpan> off_path;
  int OffPathCommands() const;  // commands in the runs
};

struct ReplayReport {
  bool ran = false;
  double object_position_error_mean = 0, object_position_error_max = 0;  // m
  double object_rotation_error_mean = 0, object_rotation_error_max = 0;  // rad
  bool success = false;
  // The floating hand's own outcome (the trajectory's metrics.success), -1 unknown.
  int reference_success = -1;
  // Per command of the re-timed path (lead moves excluded), at the
  // command's trajectory time: the simulated object against the
  // trajectory's, and the simulated flange against the trajectory's wrist.
  std::vector<double> object_position_error, object_rotation_error;  // m, rad
  std::vector<double> wrist_position_error;  // m
  std::vector<double> wrist_rotation_error;  // rad
  double wrist_position_error_mean = 0, wrist_position_error_max = 0;
  double wrist_rotation_error_mean = 0, wrist_rotation_error_max = 0;
  // Per command as above: the mean absolute error of the hand's finger
  // joints against the trajectory's (rad), and the contacts between the
  // hand and the object.
  std::vector<double> finger_error;
  std::vector<int> hand_contacts;
};

// Plan::wrist_path: the wrist path the arm was planned on.
inline constexpr const char* kWristPathTrajectory = "trajectory";  // the trajectory's own wrist
inline constexpr const char* kWristPathFloating = "floating_replay";  // PlanOnFloatingWrist's

struct Plan {
  std::string source;      // trajectory file
  std::string wrist_path = kWristPathTrajectory;
  std::string embodiment;
  double rate_hz = 50;
  Placement placement;
  std::vector<std::string> arm_joints;
  std::vector<std::string> hand_joints;
  std::vector<double> times;          // s, command k at k / rate_hz
  std::vector<double> source_times;   // the time map: each command's trajectory time (s), non-decreasing
  std::vector<ArmQ> arm;              // rad
  std::vector<Eigen::VectorXd> hand;  // the hand's joints, hand_joints order
  int lead_in = 0, lead_out = 0;      // commands of the lead moves before and after the path
  double trajectory_duration = 0;     // s, the trajectory's own
  double slowdown = 1;                // re-timed path duration / trajectory_duration
  std::vector<double> position_error, rotation_error;  // IK residual per trajectory frame
  std::vector<FrameIssue> unreachable, too_fast, over_acceleration;
  PathDeviation path_deviation;  // step 4's off_path
  ReplayReport replay;
  WristSmoothingReport wrist_smoothing;  // step 0
  bool ok = false;  // nothing listed in unreachable, too_fast, over_acceleration, off_path
};

// Step 2's joint path of one arm: the natural cubic spline through the
// IK's answers `frame_q` at the trajectory's frames (knot f at f / fps).
JointSpline JointPathThroughFrames(const std::vector<ArmQ>& frame_q, double fps);

// Step 2's test of a joint path before it is re-timed: the flange's
// largest deviation (m, rad) from the wrist path between frames along the
// joint spline through `frame_q` (the IK's answers at `wrists`' frames, at
// `fps`), sampled `samples` times per frame interval.
struct SplineDeviation {
  double position = 0, rotation = 0;
  bool Within(const PathCheckConfig& c) const {
    return position <= c.position_tolerance && rotation <= c.rotation_tolerance;
  }
};
SplineDeviation JointSplineDeviation(const std::vector<ArmQ>& frame_q, const std::vector<Pose>& wrists, double fps,
                                     int samples);

// Step 4's between-frames check of `plan`'s path commands: `wrists` are the
// wrist poses the arm was planned on, one per trajectory frame at `fps`,
// in the arm's base frame; `frame_q` the IK's joints at those frames.
PathDeviation CheckPathDeviation(const Plan& plan, const std::vector<Pose>& wrists, double fps,
                                 const std::vector<ArmQ>& frame_q, const PathCheckConfig& config);

// The floating-wrist pose of `frame` in the trajectory's world (joints
// doasido_wrist_x..rz, rotation Rx Ry Rz). Throws Error("bad_trajectory").
Pose WristPose(const retarget::HandTrajectory& t, int frame);

// Steps 1-4 above. `embodiment`'s model gives the hand joints, filled from
// the trajectory's qpos by name (a joint the trajectory lacks keeps 0).
// Throws Error("bad_trajectory") for an empty trajectory or one without a
// wrist. `placement` (may be null) fixes the placement instead of step 1's
// search; a fixed placement's reachable_fraction is the share of all
// trajectory frames the IK reached, its candidates 1.
Plan MakePlan(const retarget::HandTrajectory& trajectory, const retarget::Embodiment& embodiment,
              const PlanConfig& config, const Placement* placement = nullptr);

// Steps 2-4 for arms that share one clock (deploy plan-two): each
// trajectory at its fixed placement, one time map for all (the slowest
// joint of any arm sets the pace), lead moves as long as the longest arm's.
// Trajectories have the same frames and frame rate. Throws
// Error(kUnfollowablePath) naming the arm that holds the pace back, the
// frames where, its unreachable frames and the placement, when the
// re-timing would exceed time_scaling.max_slowdown (MakePlan too).
std::vector<Plan> MakePlansOnOneClock(const std::vector<const retarget::HandTrajectory*>& trajectories,
                                      const std::vector<const retarget::Embodiment*>& embodiments,
                                      const std::vector<Placement>& placements, const PlanConfig& config);

// The placement p_base = Rz(yaw) (p - c) + (x, y, -base_height) of step 1,
// c the mean of `wrists` on the table (z = 0).
Pose PlacementPose(double yaw, double x, double y, const std::vector<Pose>& wrists, double base_height);

// Which rig a replay simulates: the arm carrying the hand (step 5), or the
// retargeting's floating hand under the same time map, its wrist actuators
// driven by the trajectory's own wrist controls at each command's
// trajectory time: the yardstick that tells what the re-timing alone does
// to the object from what the arm does.
enum class ReplayMount { kArm, kFloating };

// Step 5 on a plan made from `trajectory`; fills plan.replay.
void ReplayPlan(Plan& plan, const retarget::HandTrajectory& trajectory,
                const retarget::Embodiment& embodiment, const std::string& scene_xml,
                const std::filesystem::path& scene_dir, double servo_omega = PlanConfig{}.servo_omega,
                ReplayMount mount = ReplayMount::kArm);

// Step 3b. The trajectory with its floating wrist joints replaced, at
// every frame, by the wrist the retargeting's floating hand reaches when
// `plan`'s commands are replayed on it (ReplayMount::kFloating, the same
// time map): the trajectory's wrist is what the floating hand did at the
// video's clock, its wrist servo lagging its controls; slowed, the same
// controls put the wrist elsewhere (10-16 mm, up to 0.18 rad in the
// bench), and that is the motion that keeps the object at the slower
// pace. The replayed wrist's offset from the trajectory's is averaged
// over `smoothing` seconds (the floating servo's jitter at contact would
// otherwise slow the re-timing down). The trajectory unchanged when it has
// no object or scene.
retarget::HandTrajectory FloatingWristTrajectory(const Plan& plan, const retarget::HandTrajectory& trajectory,
                                                 const retarget::Embodiment& embodiment,
                                                 const std::string& scene_xml,
                                                 const std::filesystem::path& scene_dir, double servo_omega,
                                                 double smoothing);

// `plan` re-planned (steps 2-4 at its placement) on
// FloatingWristTrajectory's wrist path, config.follow_rounds times (each
// round replays the last round's plan); `trajectory` is the last round's
// trajectory, the one to replay the new plan against (step 5). Both
// unchanged when follow_rounds is 0 or the trajectory has no object or
// scene.
struct FollowedPlan {
  Plan plan;
  retarget::HandTrajectory trajectory;
};
FollowedPlan PlanOnFloatingWrist(const Plan& plan, const retarget::HandTrajectory& trajectory,
                                 const retarget::Embodiment& embodiment, const PlanConfig& config,
                                 const std::string& scene_xml, const std::filesystem::path& scene_dir);

// JSON: {"format": "doasido_deploy_plan", "version": 2, "source", "embodiment",
// "rate_hz", "placement": {yaw, x, y, world_to_base: [tx,ty,tz,qw,qx,qy,qz],
// reachable_fraction, candidates, search_slowdown, manipulability},
// "arm_joints", "hand_joints", "times", "source_times", "lead_in",
// "lead_out", "trajectory_duration", "slowdown", "wrist_path" (read as
// "trajectory" when absent), "wrist_smoothing": {applied, cutoff_hz,
// position_deviation_max, rotation_deviation_max, bounded_frames} (absent
// in older files), "arm": [[6]], "hand": [[n]],
// "position_error", "rotation_error", "unreachable": [{frame, time,
// position_error, rotation_error}], "too_fast": [{frame, time, joint, speed,
// limit}], "over_acceleration": [{frame, time, joint, acceleration, limit}],
// "path_deviation": {position_max, rotation_max, worst_command,
// position_tolerance, rotation_tolerance, "off_path": [{first_command,
// last_command, commands, start_time, end_time, from_frame, to_frame,
// position_deviation, rotation_deviation, joint_jump}]} (absent in files
// from before the check: read unchecked), "replay": {...}, "ok"}. Version 1 files (no time map) read with
// source_times = times and slowdown 1.
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
