// ReplayPlan (plan.h step 5): the plan's commands on the arm + hand +
// object scene in MuJoCo (the arm servoed, or set kinematically), measured against the trajectory at each
// command's trajectory time (the time map), so a re-timed plan is judged
// by what the slowed motion does to the object, not by the video's timing.
#include <algorithm>
#include <cmath>
#include <map>

#include "deploy/plan.h"

namespace doasido::deploy {
namespace {

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

// How the hand's actuators are driven: by the trajectory's own controls
// (matched by actuator name) when it has them, else by the plan's hand
// joint positions for actuators that drive one joint.
struct HandDrive {
  std::vector<std::pair<int, int>> from_ctrl;   // (actuator, trajectory ctrl column)
  std::vector<std::pair<int, int>> from_joint;  // (actuator, plan hand index)
};

HandDrive MatchActuators(const mjModel* m, const ArmHandModel& model, const retarget::HandTrajectory& t) {
  HandDrive drive;
  std::map<int, int> hand_index;  // qpos address -> plan hand index
  for (size_t h = 0; h < model.hand_qpos.size(); ++h) hand_index[model.hand_qpos[h]] = static_cast<int>(h);
  const bool has_ctrl = !t.ctrl.empty() && t.ctrl.size() == t.qpos.size();
  for (int a = 0; a < m->nu; ++a) {
    const char* name = mj_id2name(m, mjOBJ_ACTUATOR, a);
    const auto it = name && has_ctrl ? std::find(t.ctrl_names.begin(), t.ctrl_names.end(), name) : t.ctrl_names.end();
    if (it != t.ctrl_names.end()) {
      drive.from_ctrl.emplace_back(a, static_cast<int>(it - t.ctrl_names.begin()));
      continue;
    }
    if (m->actuator_trntype[a] != mjTRN_JOINT) continue;
    const auto h = hand_index.find(m->jnt_qposadr[m->actuator_trnid[2 * a]]);
    if (h != hand_index.end()) drive.from_joint.emplace_back(a, h->second);
  }
  return drive;
}

double Mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return v.empty() ? 0 : sum / v.size();
}

double Max(const std::vector<double>& v) { return v.empty() ? 0 : *std::max_element(v.begin(), v.end()); }

}  // namespace

void ReplayPlan(Plan& plan, const retarget::HandTrajectory& trajectory, const retarget::Embodiment& embodiment,
                const std::string& scene_xml, const std::filesystem::path& scene_dir, double servo_omega) {
  if (trajectory.object_poses.empty() || scene_xml.empty() || plan.arm.empty()) return;
  const Pose base = plan.placement.world_to_base.Inverse();
  const ArmHandModel model = BuildArmHandModel(embodiment, base, scene_xml, scene_dir);
  if (model.object_qpos < 0) return;
  const mjModel* m = model.model.get();
  retarget::DataPtr data = retarget::MakeData(m);
  mjData* d = data.get();
  const HandDrive drive = MatchActuators(m, model, trajectory);
  const std::vector<double>& source = plan.source_times.size() == plan.times.size() ? plan.source_times : plan.times;
  std::vector<Pose> wrists;
  for (int f = 0; f < static_cast<int>(trajectory.qpos.size()); ++f) wrists.push_back(WristPose(trajectory, f));
  const size_t count = plan.arm.size();
  std::vector<mjtNum> mass(m->nv * m->nv);
  // The arm toward command q, speed v: set (kinematic) or servoed.
  const auto drive_arm = [&](const ArmQ& q, const ArmQ& v, bool servo) {
    if (!servo) {
      for (int n = 0; n < 6; ++n) {
        d->qpos[model.arm_qpos[n]] = q[n];
        d->qvel[model.arm_dof[n]] = v[n];
      }
      return;
    }
    // Computed torque from the last step's mass matrix and bias forces
    // (one 5-ms step old), the joints' own damping compensated.
    mj_fullM(m, mass.data(), d->qM);
    ArmQ accel;
    for (int n = 0; n < 6; ++n) {
      const int dof = model.arm_dof[n];
      accel[n] = servo_omega * servo_omega * (q[n] - d->qpos[model.arm_qpos[n]]) +
                 2 * servo_omega * (v[n] - d->qvel[dof]);
    }
    for (int r = 0; r < 6; ++r) {
      const int dof = model.arm_dof[r];
      double torque = d->qfrc_bias[dof] + m->dof_damping[dof] * d->qvel[dof];
      for (int c = 0; c < 6; ++c) torque += mass[dof * m->nv + model.arm_dof[c]] * accel[c];
      d->qfrc_applied[dof] = torque;
    }
  };
  // Command k's arm and hand drive, interpolated at fractional command f.
  const auto drive_at = [&](double f, bool with_velocity) {
    f = std::clamp(f, 0.0, static_cast<double>(count - 1));
    const size_t i = std::min(static_cast<size_t>(f), count - 1), j = std::min(i + 1, count - 1);
    const double a = f - i;
    const ArmQ arm = (1 - a) * plan.arm[i] + a * plan.arm[j];
    const ArmQ speed = with_velocity ? ArmQ((plan.arm[j] - plan.arm[i]) * plan.rate_hz) : ArmQ::Zero();
    drive_arm(arm, speed, with_velocity && servo_omega > 0);
    const VectorXd hand = (1 - a) * plan.hand[i] + a * plan.hand[j];
    for (const auto& [act, h] : drive.from_joint) d->ctrl[act] = hand[h];
    if (drive.from_ctrl.empty()) return;
    const VectorXd ctrl = RowAt(trajectory.ctrl, trajectory.fps, (1 - a) * source[i] + a * source[j]);
    for (const auto& [act, c] : drive.from_ctrl) d->ctrl[act] = ctrl[c];
  };
  drive_at(0, false);
  for (size_t h = 0; h < model.hand_qpos.size(); ++h) d->qpos[model.hand_qpos[h]] = plan.hand[0][h];
  mj_forward(m, d);

  ReplayReport r;
  if (trajectory.metrics.is_object() && trajectory.metrics.contains(retarget::kMetricSuccess)) {
    r.reference_success = trajectory.metrics.at(retarget::kMetricSuccess).get<bool>();
  }
  std::vector<double>& object_position = r.object_position_error;
  std::vector<double>& object_rotation = r.object_rotation_error;
  const size_t path_begin = plan.lead_in, path_end = count - plan.lead_out;
  const double dt = m->opt.timestep;
  const auto measure = [&](size_t k) {
    if (k < path_begin || k >= path_end) return;
    const Pose ref = PoseAt(trajectory.object_poses, trajectory.fps, source[k]);
    const mjtNum* q = d->qpos + model.object_qpos;
    const Pose sim{Quat(q[3], q[4], q[5], q[6]).normalized(), Vec3(q[0], q[1], q[2])};
    object_position.push_back((sim.t - ref.t).norm());
    object_rotation.push_back(RotationAngle(sim.q, ref.q));
    ArmQ arm;
    for (int n = 0; n < 6; ++n) arm[n] = d->qpos[model.arm_qpos[n]];
    const Pose flange = base * DhForwardPose(arm), wrist = PoseAt(wrists, trajectory.fps, source[k]);
    r.wrist_position_error.push_back((flange.t - wrist.t).norm());
    r.wrist_rotation_error.push_back(RotationAngle(flange.q, wrist.q));
  };
  size_t k = 0;
  for (long step = 0; k < count; ++step) {
    const double t = step * dt;
    while (k < count && plan.times[k] <= t + 1e-9) measure(k++);
    if (k >= count) break;
    drive_at(t * plan.rate_hz, true);
    mj_step(m, d);
  }
  r.ran = !object_position.empty();
  r.object_position_error_mean = Mean(object_position);
  r.object_position_error_max = Max(object_position);
  r.object_rotation_error_mean = Mean(object_rotation);
  r.object_rotation_error_max = Max(object_rotation);
  r.wrist_position_error_mean = Mean(r.wrist_position_error);
  r.wrist_position_error_max = Max(r.wrist_position_error);
  r.wrist_rotation_error_mean = Mean(r.wrist_rotation_error);
  r.wrist_rotation_error_max = Max(r.wrist_rotation_error);
  r.success = r.ran && r.object_position_error_mean < 0.10 && r.object_rotation_error_mean < 0.5;
  plan.replay = std::move(r);
}

}  // namespace doasido::deploy
