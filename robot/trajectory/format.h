// The robot trajectory format: what a retargeting stage writes and every
// reader (dataset export, deploy, the verify page) reads. Only core
// dependencies, so reading a trajectory needs neither a solver nor MuJoCo.
//
// A clip's trajectory lives in the artifact folder of its trajectory stage
// (TrajectoryStageOf below): kTrajectoryFile (JSON, the one readers use),
// kTrajectoryCsvFile beside it for people and spreadsheets, and for scenes
// with an object kSceneFolder/kSceneFile and kRobotSceneFile.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/config.h"
#include "core/geometry.h"

// Namespace kept from the code's first home (retarget/) so that branches in
// flight merge; robot/ holds it now.
namespace doasido::retarget {

// The two stages that write a trajectory (their adapters are
// stages/kinematic_stage.h and stages/dynamic_stage.h); the names are
// here so that a reader of trajectories needs no solver.
inline constexpr const char* kKinematicStageName = "retarget_kinematic";
inline constexpr const char* kRetargetStageName = "retarget";
// In preference order: the dynamics-aware stage's trajectory when the
// pipeline has that stage, else the kinematic one's.
inline constexpr std::array<const char*, 2> kTrajectoryStages = {kRetargetStageName,
                                                                 kKinematicStageName};
// The one rule for which stage holds a clip's trajectory: the first of
// kTrajectoryStages in `pipeline`, or "" when it has neither.
std::string TrajectoryStageOf(const std::vector<std::string>& pipeline);
bool IsTrajectoryStage(const std::string& stage);

// Artifact file names, relative to the trajectory stage's folder.
inline constexpr const char* kTrajectoryFile = "trajectory.json";
inline constexpr const char* kTrajectoryCsvFile = "trajectory.csv";
inline constexpr const char* kRobotSceneFile = "robot_scene.xml";  // hand(s) + object scene
inline constexpr const char* kSceneFolder = "scene";               // the object scene's folder
inline constexpr const char* kSceneFile = "scene.xml";             // in kSceneFolder

// Keys of HandTrajectory::metrics (the dynamics-aware stage's tracking
// errors, also its measurements): object position error E_pos (m),
// rotation error E_rot (rad), and whether both are under the success
// thresholds.
inline constexpr const char* kMetricPositionError = "e_pos";
inline constexpr const char* kMetricRotationError = "e_rot";
inline constexpr const char* kMetricSuccess = "success";

// Measurement keys of the `retarget` stage's ladder of sampler presets
// (retarget/dynamic/sampler_ladder.h): the rung whose run was kept, the
// rungs that ran (names, in order) and how many, and per rung that ran
// RungMeasurementKey(rung, what) with what = kRungSeconds (its wall time)
// or a kMetric... key above.
inline constexpr const char* kMeasurementRung = "rung";
inline constexpr const char* kMeasurementRungs = "rungs";
inline constexpr const char* kMeasurementRungsRun = "rungs_run";
inline constexpr const char* kRungSeconds = "seconds";
inline std::string RungMeasurementKey(const std::string& rung, const std::string& what) {
  return "rung_" + rung + "_" + what;
}

using Keypoints21 = Eigen::Matrix<double, 21, 3, Eigen::RowMajor>;

// The reference the dynamics-aware optimiser tracks.
struct HandTrajectory {
  std::string embodiment;
  double fps = 30;
  double scale = 1;
  std::vector<std::string> qpos_names;     // (nq)
  std::vector<Eigen::VectorXd> qpos;       // (T, nq) robot joint positions, wrist first
  std::vector<bool> valid;                 // (T) human hand seen; else the pose is held
  std::vector<double> fingertip_error;     // (T) mean fingertip distance to target, m
  std::vector<Pose> object_poses;          // (T) object->world, or empty
  // (T) the human keypoints the hand followed: scaled by `scale` about the
  // wrist, world frame; NaN where the hand was not seen. Empty in files
  // written before it was recorded.
  std::vector<Keypoints21> reference_keypoints;
  // Written by the dynamics-aware `retarget` stage; empty from retarget_kinematic.
  std::vector<std::string> ctrl_names;     // (nu) actuator names
  std::vector<Eigen::VectorXd> ctrl;       // (T, nu) position targets, or empty
  Json metrics = Json::object();           // kMetric* keys above
};

// JSON: {"embodiment", "fps", "scale", "qpos_names", "qpos": [[...]], "valid",
// "fingertip_error", "object_poses": [[tx,ty,tz,qw,qx,qy,qz]]} plus, when
// present, "reference_keypoints": [[x0,y0,z0,...,x20,y20,z20] or null],
// "ctrl_names", "ctrl": [[...]] and "metrics". Throws Error("io").
void WriteTrajectoryJson(const HandTrajectory& t, const std::filesystem::path& path);
// CSV: frame,time,valid,fingertip_error,<qpos names...>[,obj_tx..obj_qz]; one row a frame.
void WriteTrajectoryCsv(const HandTrajectory& t, const std::filesystem::path& path);
// Reads WriteTrajectoryJson's output. Throws Error("bad_trajectory").
HandTrajectory ReadTrajectoryJson(const std::filesystem::path& path);

// Reads a keypoint CSV: header k0_x,k0_y,k0_z,...,k20_z then one row of 63
// numbers (metres) per frame. Throws Error("bad_keypoints") naming file and line.
std::vector<Keypoints21> ReadKeypointCsv(const std::filesystem::path& path);

// Mean and 95th percentile (nearest rank) of the finite entries of a
// trajectory's fingertip_error, m; `frames` counts them (0: mean 0, p95 NaN).
// The one definition behind the stage's measurements and the CLI's printout.
struct FingertipErrorStats {
  int frames = 0;
  double mean = 0;
  double p95 = 0;
};
FingertipErrorStats SummarizeFingertipError(const std::vector<double>& error);

// Two-hand trajectories (retarget/bimanual_retarget.h writes them): one
// trajectory over both hands' variables, names prefixed kLeftPrefix and
// kRightPrefix, embodiment "<left>+<right>".
inline constexpr const char* kLeftPrefix = "l_";
inline constexpr const char* kRightPrefix = "r_";
inline constexpr char kBimanualSeparator = '+';
inline bool IsBimanualEmbodiment(const std::string& name) {
  return name.find(kBimanualSeparator) != std::string::npos;
}
// A two-hand trajectory (BimanualRun::trajectory, or its trajectory.json)
// as the left and the right hand's own trajectories: variables without
// their prefix, the embodiment's two names, object poses and metrics on
// both; controls split by actuator name the same way. Throws
// Error("bad_trajectory") for a trajectory that is not a two-hand one.
std::pair<HandTrajectory, HandTrajectory> SplitBimanualTrajectory(const HandTrajectory& both);
// The inverse for positions: one trajectory over both hands' variables,
// names prefixed, embodiment "<left>+<right>" (the right's other fields).
HandTrajectory CombineBimanualTrajectories(const HandTrajectory& left, const HandTrajectory& right);

}  // namespace doasido::retarget
