// ReplayPlan (plan.h step 5): the plan's commands on the arm + hand +
// object scene in MuJoCo (the arm servoed, or set kinematically), measured against the trajectory at each
// command's trajectory time (the time map), so a re-timed plan is judged
// by what the slowed motion does to the object, not by the video's timing.
#include <algorithm>
#include <cmath>
#include <functional>
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

void DriveHand(const HandDrive& drive, const retarget::HandTrajectory& t, double s, mjData* d) {
  if (!drive.from_joint.empty()) {
    const VectorXd qpos = RowAt(t.qpos, t.fps, s);
    for (const auto& [act, c] : drive.from_joint) d->ctrl[act] = qpos[c];
  }
  if (drive.from_ctrl.empty()) return;
  const VectorXd ctrl = RowAt(t.ctrl, t.fps, s);
  for (const auto& [act, c] : drive.from_ctrl) d->ctrl[act] = ctrl[c];
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
// One replay: the simulation of a plan's commands on a rig, driven and
// measured command by command (the steps of Run below).
class ReplayRun {
 public:
  // Sees the state reached at every command's time (lead moves too).
  using Observer = std::function<void(size_t command, const mjData* d)>;

  ReplayRun(const Plan& plan, const retarget::HandTrajectory& trajectory, const Rig& rig, double servo_omega)
      : plan_(plan), t_(trajectory), rig_(rig), omega_(servo_omega), m_(rig.model.get()),
        data_(retarget::MakeData(m_)), d_(data_.get()), drive_(MatchActuators(m_, rig.joints, trajectory)),
        source_(plan.source_times.size() == plan.times.size() ? plan.source_times : plan.times),
        count_(plan.arm.size()), floating_(!rig.wrist_qpos.empty()), mass_(m_->nv * m_->nv) {
    for (int f = 0; f < static_cast<int>(t_.qpos.size()); ++f) wrists_.push_back(WristPose(t_, f));
  }

  // The contacts of the object with anything but the world (table, floor).
  static int HandContacts(const mjModel* m, const mjData* d, int object_body) {
    int contacts = 0;
    for (int c = 0; c < d->ncon; ++c) {
      const int b1 = m->geom_bodyid[d->contact[c].geom1], b2 = m->geom_bodyid[d->contact[c].geom2];
      const int other = b1 == object_body ? b2 : b2 == object_body ? b1 : -1;
      contacts += other > 0;
    }
    return contacts;
  }

  ReplayReport Run(const Observer& observe = {}) {
    Start();
    const double dt = m_->opt.timestep;
    size_t k = 0;
    for (long step = 0; k < count_; ++step) {
      const double t = step * dt;
      for (; k < count_ && plan_.times[k] <= t + 1e-9; ++k) {
        Measure(k);
        if (observe) observe(k, d_);
      }
      if (k >= count_) break;
      Drive(t * plan_.rate_hz, false);
      mj_step(m_, d_);
    }
    Summarise(r_);
    return r_;
  }

 private:
  // Fractional command index f as the commands i, j around it and the weight of j.
  struct Between {
    size_t i, j;
    double a;
  };
  Between At(double f) const {
    f = std::clamp(f, 0.0, static_cast<double>(count_ - 1));
    const size_t i = std::min(static_cast<size_t>(f), count_ - 1);
    return {i, std::min(i + 1, count_ - 1), f - i};
  }

  ArmQ ArmAt(double f) const {
    const Between b = At(f);
    return ArmQ((1 - b.a) * plan_.arm[b.i] + b.a * plan_.arm[b.j]);
  }

  // The arm's joints at command f: set at the start (at rest) or when
  // there is no servo, else servoed toward the command with its speed and
  // acceleration by central differences over one command (the plan's own
  // finite differences).
  void DriveArm(double f, bool start) {
    const ArmQ q = ArmAt(f), v = (ArmAt(f + 0.5) - ArmAt(f - 0.5)) * plan_.rate_hz;
    if (start || omega_ <= 0) {
      for (int n = 0; n < 6; ++n) {
        d_->qpos[rig_.arm_qpos[n]] = q[n];
        d_->qvel[rig_.arm_dof[n]] = start ? 0 : v[n];
      }
      return;
    }
    const ArmQ acc = (ArmAt(f + 1) - 2 * q + ArmAt(f - 1)) * plan_.rate_hz * plan_.rate_hz;
    ServoArm(m_, d_, rig_, q, v, acc, omega_, mass_);
  }

  // The hand's actuators at command f's trajectory time (the time map).
  void DriveHand(double f) {
    const Between b = At(f);
    const double s = (1 - b.a) * source_[b.i] + b.a * source_[b.j];
    replay::DriveHand(drive_, t_, s, d_);
  }

  void Drive(double f, bool start) {
    if (!floating_) DriveArm(f, start);
    DriveHand(f);
  }

  // The first command's arm at rest, the trajectory's joints at its first time.
  void Start() {
    Drive(0, true);
    const VectorXd first = RowAt(t_.qpos, t_.fps, source_[0]);
    for (const auto& [adr, c] : rig_.joints) d_->qpos[adr] = first[c];
    mj_forward(m_, d_);
    if (t_.metrics.is_object() && t_.metrics.contains(retarget::kMetricSuccess)) {
      r_.reference_success = t_.metrics.at(retarget::kMetricSuccess).get<bool>();
    }
  }

  // Command k of the path (lead moves are not measured).
  void Measure(size_t k) {
    if (k < static_cast<size_t>(plan_.lead_in) || k >= count_ - plan_.lead_out) return;
    const double s = source_[k];
    const Pose ref = PoseAt(t_.object_poses, t_.fps, s);
    const mjtNum* q = d_->qpos + rig_.object_qpos;
    const Pose sim{Quat(q[3], q[4], q[5], q[6]).normalized(), Vec3(q[0], q[1], q[2])};
    r_.object_position_error.push_back((sim.t - ref.t).norm());
    r_.object_rotation_error.push_back(RotationAngle(sim.q, ref.q));
    MeasureWrist(s);
    MeasureHand(s);
  }

  // The simulated body that carries the hand (the arm's flange, the
  // floating wrist's mount), as MuJoCo placed it: a mismatch between the
  // arm's model and its DH kinematics shows here.
  void MeasureWrist(double s) {
    mj_kinematics(m_, d_);  // the poses of the state reached, not of the step before
    const mjtNum* p = d_->xpos + 3 * rig_.wrist_body;
    const mjtNum* o = d_->xquat + 4 * rig_.wrist_body;
    const Pose flange{Quat(o[0], o[1], o[2], o[3]).normalized(), Vec3(p[0], p[1], p[2])};
    const Pose wrist = PoseAt(wrists_, t_.fps, s);
    r_.wrist_position_error.push_back((flange.t - wrist.t).norm());
    r_.wrist_rotation_error.push_back(RotationAngle(flange.q, wrist.q));
  }

  // The finger joints' mean error against the trajectory's, and the
  // hand's contacts with the object.
  void MeasureHand(double s) {
    const VectorXd target = RowAt(t_.qpos, t_.fps, s);
    double finger = 0;
    int fingers = 0;
    for (const auto& [adr, c] : rig_.joints) {
      if (std::find(rig_.wrist_qpos.begin(), rig_.wrist_qpos.end(), adr) != rig_.wrist_qpos.end()) continue;
      finger += std::abs(d_->qpos[adr] - target[c]);
      ++fingers;
    }
    r_.finger_error.push_back(fingers ? finger / fingers : 0);
    r_.hand_contacts.push_back(HandContacts(m_, d_, rig_.object_body));
  }

  const Plan& plan_;
  const retarget::HandTrajectory& t_;
  const Rig& rig_;
  const double omega_;
  const mjModel* m_;
  retarget::DataPtr data_;
  mjData* d_;
  const HandDrive drive_;
  const std::vector<double>& source_;
  const size_t count_;
  const bool floating_;
  std::vector<mjtNum> mass_;
  std::vector<Pose> wrists_;
  ReplayReport r_;
};

// At trajectory time s, between the samples (times[c], times[c + 1]) of
// non-decreasing `times`: c advanced from its last value (s non-decreasing
// over the calls) and the weight of c + 1.
double Bracket(const std::vector<double>& times, double s, size_t& c) {
  while (c + 2 < times.size() && times[c + 1] < s) ++c;
  const size_t n = std::min(c + 1, times.size() - 1);
  const double span = times[n] - times[c];
  return span > 0 ? std::clamp((s - times[c]) / span, 0.0, 1.0) : 0.0;
}

// Centred moving average over 2 half + 1 rows, shrunk at the ends.
std::vector<VectorXd> MovingAverage(const std::vector<VectorXd>& rows, int half) {
  std::vector<VectorXd> out;
  const int n = static_cast<int>(rows.size());
  for (int i = 0; i < n; ++i) {
    const int h = std::min({half, i, n - 1 - i});
    VectorXd sum = VectorXd::Zero(rows[i].size());
    for (int j = i - h; j <= i + h; ++j) sum += rows[j];
    out.push_back(sum / (2 * h + 1));
  }
  return out;
}

// FloatingWristTrajectory's replay: per trajectory frame, the floating
// wrist's offset from the trajectory's (wrist joints, `columns` order) and
// whether the hand touched the object.
struct ReplayedWrist {
  std::vector<int> columns;  // the wrist joints' trajectory qpos columns
  std::vector<VectorXd> offsets;
  std::vector<bool> touching;
};

ReplayedWrist ReplayWrist(const Plan& plan, const retarget::HandTrajectory& trajectory, const Rig& rig,
                          double servo_omega) {
  ReplayedWrist out;
  std::vector<int> qpos;  // the wrist joints' addresses
  for (const auto& [adr, c] : rig.joints) {
    if (std::find(rig.wrist_qpos.begin(), rig.wrist_qpos.end(), adr) == rig.wrist_qpos.end()) continue;
    qpos.push_back(adr);
    out.columns.push_back(c);
  }
  std::vector<double> times;   // the path's commands' trajectory times
  std::vector<VectorXd> rows;  // the simulated wrist joints there
  std::vector<int> contacts;
  const size_t begin = plan.lead_in, end = plan.arm.size() - plan.lead_out;
  ReplayRun(plan, trajectory, rig, servo_omega).Run([&](size_t k, const mjData* d) {
    if (k < begin || k >= end) return;
    VectorXd w(qpos.size());
    for (size_t n = 0; n < qpos.size(); ++n) w[n] = d->qpos[qpos[n]];
    times.push_back(plan.source_times[k]);
    rows.push_back(w);
    contacts.push_back(ReplayRun::HandContacts(rig.model.get(), d, rig.object_body));
  });
  size_t c = 0;
  for (size_t f = 0; f < trajectory.qpos.size(); ++f) {
    const double a = Bracket(times, f / trajectory.fps, c);
    const size_t n = std::min(c + 1, rows.size() - 1);
    VectorXd w = (1 - a) * rows[c] + a * rows[n];
    for (size_t j = 0; j < qpos.size(); ++j) w[j] -= trajectory.qpos[f][out.columns[j]];
    out.offsets.push_back(w);
    out.touching.push_back(contacts[c] > 0 || contacts[n] > 0);
  }
  return out;
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
  plan.replay = ReplayRun(plan, trajectory, rig, servo_omega).Run();
}

retarget::HandTrajectory FloatingWristTrajectory(const Plan& plan, const retarget::HandTrajectory& trajectory,
                                                 const retarget::Embodiment& embodiment,
                                                 const std::string& scene_xml,
                                                 const std::filesystem::path& scene_dir, double servo_omega,
                                                 double smoothing) {
  if (trajectory.object_poses.empty() || scene_xml.empty() || plan.arm.size() <= size_t(plan.lead_in + plan.lead_out)) {
    return trajectory;
  }
  const Rig rig = FloatingRig(embodiment, trajectory, scene_xml, scene_dir);
  if (rig.object_qpos < 0) return trajectory;
  const ReplayedWrist replayed = ReplayWrist(plan, trajectory, rig, servo_omega);
  // The offset applies in contact only (ramped over the smoothing window):
  // in free motion the trajectory's own path, as smooth as the video's.
  const int half = static_cast<int>(std::lround(0.5 * smoothing * trajectory.fps));
  const std::vector<VectorXd> offsets = MovingAverage(replayed.offsets, half);
  std::vector<VectorXd> touching;
  for (size_t f = 0; f < replayed.touching.size(); ++f) {
    bool near = false;
    for (int g = std::max(0, int(f) - half); g <= std::min(int(f) + half, int(replayed.touching.size()) - 1); ++g) {
      near = near || replayed.touching[g];
    }
    touching.push_back(VectorXd::Constant(1, near ? 1.0 : 0.0));
  }
  touching = MovingAverage(touching, half);
  retarget::HandTrajectory followed = trajectory;
  for (size_t f = 0; f < followed.qpos.size(); ++f) {
    for (size_t n = 0; n < replayed.columns.size(); ++n) {
      followed.qpos[f][replayed.columns[n]] += touching[f][0] * offsets[f][n];
    }
  }
  return followed;
}

}  // namespace doasido::deploy
