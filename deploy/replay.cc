// ReplayPlan (plan.h step 5): the plan's commands on the arm + hand +
// object scene in MuJoCo (the arm servoed, or set kinematically), measured against the trajectory at each
// command's trajectory time (the time map), so a re-timed plan is judged
// by what the slowed motion does to the object, not by the video's timing.
#include <algorithm>
#include <cmath>
#include <map>

#include "robot/embodiment.h"

#include "deploy/plan.h"
#include "deploy/replay_rig.h"

namespace doasido::deploy {
namespace replay {

using Eigen::VectorXd;

// poses[] at `fps`, interpolated at time s (slerp / linear).
Pose PoseAt(const std::vector<Pose>& poses, double fps, double s) {
  const int n = static_cast<int>(poses.size());
  const double f = std::clamp(s * fps, 0.0, static_cast<double>(n - 1));
  const int i = std::min(static_cast<int>(f), n - 1), j = std::min(i + 1, n - 1);
  const double a = f - i;
  return {poses[i].q.slerp(a, poses[j].q).normalized(), (1 - a) * poses[i].t + a * poses[j].t};
}

VectorXd RowAt(const std::vector<VectorXd>& rows, double fps, double s) {
  const int n = static_cast<int>(rows.size());
  const double f = std::clamp(s * fps, 0.0, static_cast<double>(n - 1));
  const int i = std::min(static_cast<int>(f), n - 1), j = std::min(i + 1, n - 1);
  const double a = f - i;
  return (1 - a) * rows[i] + a * rows[j];
}

// joints: (qpos address, trajectory qpos column) of the rig's joints the trajectory has.
HandDrive MatchActuators(const mjModel* m, const std::vector<std::pair<int, int>>& joints,
                         const retarget::HandTrajectory& t) {
  HandDrive drive;
  const std::map<int, int> column(joints.begin(), joints.end());
  const bool has_ctrl = !t.ctrl.empty() && t.ctrl.size() == t.qpos.size();
  for (int a = 0; a < m->nu; ++a) {
    const char* name = mj_id2name(m, mjOBJ_ACTUATOR, a);
    const auto it = name && has_ctrl ? std::find(t.ctrl_names.begin(), t.ctrl_names.end(), name) : t.ctrl_names.end();
    if (it != t.ctrl_names.end()) {
      drive.from_ctrl.emplace_back(a, static_cast<int>(it - t.ctrl_names.begin()));
      continue;
    }
    if (m->actuator_trntype[a] != mjTRN_JOINT) continue;
    const auto c = column.find(m->jnt_qposadr[m->actuator_trnid[2 * a]]);
    if (c != column.end()) drive.from_joint.emplace_back(a, c->second);
  }
  return drive;
}

double Mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return v.empty() ? 0 : sum / v.size();
}

double Max(const std::vector<double>& v) { return v.empty() ? 0 : *std::max_element(v.begin(), v.end()); }

// The trajectory's joints `m` has, by name.
std::vector<std::pair<int, int>> TrajectoryJoints(const mjModel* m, const retarget::HandTrajectory& t) {
  std::vector<std::pair<int, int>> joints;
  for (size_t c = 0; c < t.qpos_names.size(); ++c) {
    const int j = mj_name2id(m, mjOBJ_JOINT, t.qpos_names[c].c_str());
    if (j >= 0) joints.emplace_back(m->jnt_qposadr[j], static_cast<int>(c));
  }
  return joints;
}

Rig ArmRig(const retarget::Embodiment& embodiment, const retarget::HandTrajectory& t, const Pose& base,
           const std::string& scene_xml, const std::filesystem::path& scene_dir) {
  ArmHandModel model = BuildArmHandModel(embodiment, base, scene_xml, scene_dir);
  Rig rig{.object_qpos = model.object_qpos, .arm_qpos = model.arm_qpos, .arm_dof = model.arm_dof,
          .wrist_body = model.flange_body};
  rig.model = std::move(model.model);
  rig.joints = TrajectoryJoints(rig.model.get(), t);
  rig.object_body = model.object_body;
  return rig;
}

Rig FloatingRig(const retarget::Embodiment& embodiment, const retarget::HandTrajectory& t,
                const std::string& scene_xml, const std::filesystem::path& scene_dir) {
  retarget::Embodiment floating = embodiment;
  floating.floating_base = true;
  retarget::HandModel hand = retarget::BuildHandModel(floating, scene_xml, scene_dir);
  Rig rig{.wrist_qpos = hand.wrist_qpos};
  rig.model = std::move(hand.model);
  const mjModel* m = rig.model.get();
  rig.wrist_body = mj_name2id(m, mjOBJ_BODY, retarget::kWristMountBody);
  rig.joints = TrajectoryJoints(m, t);
  const int object = mj_name2id(m, mjOBJ_BODY, "object");
  if (object >= 0 && m->body_jntnum[object] > 0 && m->jnt_type[m->body_jntadr[object]] == mjJNT_FREE) {
    rig.object_qpos = m->jnt_qposadr[m->body_jntadr[object]];
    rig.object_body = object;
  }
  return rig;
}

// The arm servo (PlanConfig::servo_omega): computed torque toward the
// command q at speed v and acceleration a, a PD on the joints critically
// damped at omega plus the command's acceleration, through the last step's
// mass matrix and bias forces (one step old), the joints' own damping
// compensated.
void ServoArm(const mjModel* m, mjData* d, const Rig& rig, const ArmQ& q, const ArmQ& v, const ArmQ& a,
              double omega, std::vector<mjtNum>& mass) {
  mj_fullM(m, mass.data(), d->qM);
  ArmQ accel;
  for (int n = 0; n < 6; ++n) {
    const int dof = rig.arm_dof[n];
    accel[n] = a[n] + omega * omega * (q[n] - d->qpos[rig.arm_qpos[n]]) + 2 * omega * (v[n] - d->qvel[dof]);
  }
  for (int r = 0; r < 6; ++r) {
    const int dof = rig.arm_dof[r];
    double torque = d->qfrc_bias[dof] + m->dof_damping[dof] * d->qvel[dof];
    for (int c = 0; c < 6; ++c) torque += mass[dof * m->nv + rig.arm_dof[c]] * accel[c];
    d->qfrc_applied[dof] = torque;
  }
}

void Summarise(ReplayReport& r) {
  r.ran = !r.object_position_error.empty();
  r.object_position_error_mean = Mean(r.object_position_error);
  r.object_position_error_max = Max(r.object_position_error);
  r.object_rotation_error_mean = Mean(r.object_rotation_error);
  r.object_rotation_error_max = Max(r.object_rotation_error);
  r.wrist_position_error_mean = Mean(r.wrist_position_error);
  r.wrist_position_error_max = Max(r.wrist_position_error);
  r.wrist_rotation_error_mean = Mean(r.wrist_rotation_error);
  r.wrist_rotation_error_max = Max(r.wrist_rotation_error);
  // REFERENCE.md section 5's success, as the retargeting's metrics judge it.
  r.success = r.ran && r.object_position_error_mean < 0.10 && r.object_rotation_error_mean < 0.5;
}

}  // namespace replay
namespace {

using namespace replay;

// Step 5 on `rig` (arm when rig.arm_qpos is used, floating when rig.wrist_qpos is set).
ReplayReport Replay(const Plan& plan, const retarget::HandTrajectory& trajectory, const Rig& rig,
                    double servo_omega) {
  const mjModel* m = rig.model.get();
  const bool floating = !rig.wrist_qpos.empty();
  retarget::DataPtr data = retarget::MakeData(m);
  mjData* d = data.get();
  const HandDrive drive = MatchActuators(m, rig.joints, trajectory);
  const std::vector<double>& source = plan.source_times.size() == plan.times.size() ? plan.source_times : plan.times;
  std::vector<Pose> wrists;
  for (int f = 0; f < static_cast<int>(trajectory.qpos.size()); ++f) wrists.push_back(WristPose(trajectory, f));
  const size_t count = plan.arm.size();
  std::vector<mjtNum> mass(m->nv * m->nv);
  const auto arm_at = [&](double f) {
    f = std::clamp(f, 0.0, static_cast<double>(count - 1));
    const size_t i = std::min(static_cast<size_t>(f), count - 1), j = std::min(i + 1, count - 1);
    const double a = f - i;
    return ArmQ((1 - a) * plan.arm[i] + a * plan.arm[j]);
  };
  // Command f's drive (fractional command index): the arm's joints (set
  // at the start, servoed after), the hand's actuators.
  const auto drive_at = [&](double f, bool start) {
    f = std::clamp(f, 0.0, static_cast<double>(count - 1));
    const size_t i = std::min(static_cast<size_t>(f), count - 1), j = std::min(i + 1, count - 1);
    const double a = f - i;
    if (!floating) {
      // Speed and acceleration of the commanded path by central differences
      // over one command (the plan's own finite differences).
      const ArmQ q = arm_at(f), v = (arm_at(f + 0.5) - arm_at(f - 0.5)) * plan.rate_hz;
      const ArmQ acc = (arm_at(f + 1) - 2 * q + arm_at(f - 1)) * plan.rate_hz * plan.rate_hz;
      if (start || servo_omega <= 0) {
        for (int n = 0; n < 6; ++n) {
          d->qpos[rig.arm_qpos[n]] = q[n];
          d->qvel[rig.arm_dof[n]] = start ? 0 : v[n];
        }
      } else {
        ServoArm(m, d, rig, q, v, acc, servo_omega, mass);
      }
    }
    const double s = (1 - a) * source[i] + a * source[j];
    if (!drive.from_joint.empty()) {
      const VectorXd qpos = RowAt(trajectory.qpos, trajectory.fps, s);
      for (const auto& [act, c] : drive.from_joint) d->ctrl[act] = qpos[c];
    }
    if (drive.from_ctrl.empty()) return;
    const VectorXd ctrl = RowAt(trajectory.ctrl, trajectory.fps, s);
    for (const auto& [act, c] : drive.from_ctrl) d->ctrl[act] = ctrl[c];
  };
  drive_at(0, true);
  const VectorXd first = RowAt(trajectory.qpos, trajectory.fps, source[0]);
  for (const auto& [adr, c] : rig.joints) d->qpos[adr] = first[c];
  mj_forward(m, d);

  ReplayReport r;
  if (trajectory.metrics.is_object() && trajectory.metrics.contains(retarget::kMetricSuccess)) {
    r.reference_success = trajectory.metrics.at(retarget::kMetricSuccess).get<bool>();
  }
  const size_t path_begin = plan.lead_in, path_end = count - plan.lead_out;
  const auto measure = [&](size_t k) {
    if (k < path_begin || k >= path_end) return;
    const Pose ref = PoseAt(trajectory.object_poses, trajectory.fps, source[k]);
    const mjtNum* q = d->qpos + rig.object_qpos;
    const Pose sim{Quat(q[3], q[4], q[5], q[6]).normalized(), Vec3(q[0], q[1], q[2])};
    r.object_position_error.push_back((sim.t - ref.t).norm());
    r.object_rotation_error.push_back(RotationAngle(sim.q, ref.q));
    // The simulated body that carries the hand (the arm's flange, the
    // floating wrist's mount), as MuJoCo placed it: a mismatch between the
    // arm's model and its DH kinematics shows here.
    mj_kinematics(m, d);  // the poses of the state reached, not of the step before
    const mjtNum* p = d->xpos + 3 * rig.wrist_body;
    const mjtNum* o = d->xquat + 4 * rig.wrist_body;
    const Pose flange{Quat(o[0], o[1], o[2], o[3]).normalized(), Vec3(p[0], p[1], p[2])};
    const Pose wrist = PoseAt(wrists, trajectory.fps, source[k]);
    r.wrist_position_error.push_back((flange.t - wrist.t).norm());
    r.wrist_rotation_error.push_back(RotationAngle(flange.q, wrist.q));
    const VectorXd target = RowAt(trajectory.qpos, trajectory.fps, source[k]);
    double finger = 0;
    int fingers = 0;
    for (const auto& [adr, c] : rig.joints) {
      if (std::find(rig.wrist_qpos.begin(), rig.wrist_qpos.end(), adr) != rig.wrist_qpos.end()) continue;
      finger += std::abs(d->qpos[adr] - target[c]);
      ++fingers;
    }
    r.finger_error.push_back(fingers ? finger / fingers : 0);
    int contacts = 0;
    for (int c = 0; c < d->ncon; ++c) {
      const int b1 = m->geom_bodyid[d->contact[c].geom1], b2 = m->geom_bodyid[d->contact[c].geom2];
      const int other = b1 == rig.object_body ? b2 : b2 == rig.object_body ? b1 : -1;
      contacts += other > 0;  // not the world (table, floor)
    }
    r.hand_contacts.push_back(contacts);
  };
  const double dt = m->opt.timestep;
  size_t k = 0;
  for (long step = 0; k < count; ++step) {
    const double t = step * dt;
    while (k < count && plan.times[k] <= t + 1e-9) measure(k++);
    if (k >= count) break;
    drive_at(t * plan.rate_hz, false);
    mj_step(m, d);
  }
  Summarise(r);
  return r;
}

}  // namespace

void ReplayPlan(Plan& plan, const retarget::HandTrajectory& trajectory, const retarget::Embodiment& embodiment,
                const std::string& scene_xml, const std::filesystem::path& scene_dir, double servo_omega,
                ReplayMount mount) {
  if (trajectory.object_poses.empty() || scene_xml.empty() || plan.arm.empty()) return;
  const Pose base = plan.placement.world_to_base.Inverse();
  const Rig rig = mount == ReplayMount::kArm ? ArmRig(embodiment, trajectory, base, scene_xml, scene_dir)
                                             : FloatingRig(embodiment, trajectory, scene_xml, scene_dir);
  if (rig.object_qpos < 0) return;
  plan.replay = Replay(plan, trajectory, rig, servo_omega);
}

}  // namespace doasido::deploy
