// The pieces of the one-arm replay (replay.cc) that the two-arm replay
// (bimanual_replay.cc) reuses: interpolation of the trajectory at a
// trajectory time, matching the rig's actuators to the trajectory's
// controls, the simulated rig, the arm servo and the report's summary.
// Internal to deploy/; defined in replay.cc.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "deploy/plan.h"
#include "robot/mj_model.h"

namespace doasido::deploy::replay {

// poses[] at `fps`, interpolated at time s (slerp / linear).
Pose PoseAt(const std::vector<Pose>& poses, double fps, double s);
Eigen::VectorXd RowAt(const std::vector<Eigen::VectorXd>& rows, double fps, double s);

// How the rig's actuators are driven: by the trajectory's own controls
// (matched by actuator name) when it has them, else, for actuators that
// drive one joint the trajectory has, by that joint's trajectory position.
struct HandDrive {
  std::vector<std::pair<int, int>> from_ctrl;   // (actuator, trajectory ctrl column)
  std::vector<std::pair<int, int>> from_joint;  // (actuator, trajectory qpos column)
};

// joints: (qpos address, trajectory qpos column) of the rig's joints the trajectory has.
HandDrive MatchActuators(const mjModel* m, const std::vector<std::pair<int, int>>& joints,
                         const retarget::HandTrajectory& t);

// The rig's hand actuators set from the trajectory at trajectory time s.
void DriveHand(const HandDrive& drive, const retarget::HandTrajectory& t, double s, mjData* d);

double Mean(const std::vector<double>& v);
double Max(const std::vector<double>& v);

// The simulated rig of a replay: the arm with the hand on its flange, or
// the floating hand of the retargeting (its wrist actuators driven by the
// trajectory's own wrist controls), in the trajectory's scene.
struct Rig {
  retarget::ModelPtr model;
  int object_qpos = -1;
  std::array<int, 6> arm_qpos{}, arm_dof{};  // arm only
  // (qpos address, trajectory qpos column) of the trajectory's joints the
  // rig has (the fingers; the floating wrist too): set from the trajectory
  // at the start, and the targets of their position actuators when the
  // trajectory has no controls.
  std::vector<std::pair<int, int>> joints;
  std::vector<int> wrist_qpos;               // floating only: x y z rx ry rz
  int wrist_body = -1;                       // the body carrying the hand: flange or floating mount
  int object_body = -1;
};

// The trajectory's joints `m` has, by name.
std::vector<std::pair<int, int>> TrajectoryJoints(const mjModel* m, const retarget::HandTrajectory& t);

Rig ArmRig(const retarget::Embodiment& embodiment, const retarget::HandTrajectory& t, const Pose& base,
           const std::string& scene_xml, const std::filesystem::path& scene_dir);
Rig FloatingRig(const retarget::Embodiment& embodiment, const retarget::HandTrajectory& t,
                const std::string& scene_xml, const std::filesystem::path& scene_dir);

// The arm servo (PlanConfig::servo_omega): computed torque toward the
// command q at speed v and acceleration a, a PD on the joints critically
// damped at omega plus the command's acceleration, through the last step's
// mass matrix and bias forces (one step old), the joints' own damping
// compensated.
void ServoArm(const mjModel* m, mjData* d, const Rig& rig, const ArmQ& q, const ArmQ& v, const ArmQ& a,
              double omega, std::vector<mjtNum>& mass);

// The means, maxima and success of a report from its per-command errors.
void Summarise(ReplayReport& r);

}  // namespace doasido::deploy::replay
