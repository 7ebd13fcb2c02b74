// ReplayBimanualPlan (bimanual.h): both arms of a two-arm plan, each with
// its hand, and the object in one MuJoCo scene on the plan's one clock;
// the one-arm replay's pieces (replay_rig.h) per side. The model is the
// retargeting's two-hand model with each floating wrist replaced by an arm
// at its base (or, ReplayMount::kFloating, that model itself): each side's
// MJCF prefixed as the two-hand trajectory's variables are (kLeftPrefix,
// kRightPrefix), so the trajectory's joints and controls match by name.
#include <algorithm>
#include <cmath>

#include <tinyxml2.h>

#include "core/error.h"
#include "deploy/bimanual.h"
#include "deploy/replay_rig.h"
#include "robot/mjcf_compat.h"
#include "robot/mjcf_text.h"

namespace doasido::deploy {
namespace {

using namespace replay;
using Eigen::VectorXd;

// One side of the two-arm rig: its arm's joints (the servo reads
// arm_qpos / arm_dof of `arm` only), the body carrying its hand, its
// finger joints and its wrist path in the trajectory's world.
struct Side {
  Rig arm;
  const Plan* plan = nullptr;
  std::string prefix;
  std::vector<std::pair<int, int>> fingers;  // (qpos address, two-hand trajectory column)
  std::vector<Pose> wrists;                  // per trajectory frame
  ReplayReport report;
};

std::string SideXml(const retarget::Embodiment& e, const Plan& plan, ReplayMount mount, const std::string& prefix) {
  std::string xml;
  if (mount == ReplayMount::kArm) {
    xml = BuildArmHandModel(e, plan.placement.world_to_base.Inverse()).xml;
  } else {
    retarget::Embodiment floating = e;
    floating.floating_base = true;
    xml = retarget::BuildHandModel(floating).xml;
  }
  return retarget::PrefixMjcfNames(xml, prefix, e.name);
}

// Right side first, as the retargeting's two-hand model (its options win).
retarget::ModelPtr TwoSideModel(const BimanualPlan& plan, const retarget::Embodiment& left_hand,
                                const retarget::Embodiment& right_hand, ReplayMount mount,
                                const std::string& scene_xml, const std::filesystem::path& scene_dir) {
  tinyxml2::XMLDocument doc;
  retarget::ParseMjcfText(SideXml(right_hand, plan.right, mount, retarget::kRightPrefix), right_hand.name, doc);
  retarget::AppendRootChildren(doc, SideXml(left_hand, plan.left, mount, retarget::kLeftPrefix), left_hand.name);
  retarget::AppendRootChildren(
      doc, retarget::PrepareMjcfText(scene_xml, scene_dir, (scene_dir / "scene").string()).xml, "scene");
  return retarget::CompileMjcfText(retarget::PrintMjcf(doc), "two-arm replay");
}

bool StartsWith(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }

int RequireId(const mjModel* m, int type, const std::string& name) {
  const int id = retarget::NameToId(m, type, name);
  if (id < 0) throw Error("bad_mjcf", "the two-arm replay's model has no " + name, {.file = "two-arm replay"});
  return id;
}

Side MakeSide(const mjModel* m, const Plan& plan, const std::string& prefix, ReplayMount mount,
              const std::vector<std::pair<int, int>>& joints, const retarget::HandTrajectory& both,
              const retarget::HandTrajectory& own) {
  Side s{.plan = &plan, .prefix = prefix};
  const std::string carrier = mount == ReplayMount::kArm ? "ur3e_flange" : retarget::kWristMountBody;
  s.arm.wrist_body = RequireId(m, mjOBJ_BODY, prefix + carrier);
  if (mount == ReplayMount::kArm) {
    for (int i = 0; i < 6; ++i) {
      const int j = RequireId(m, mjOBJ_JOINT, prefix + Ur3eJointNames()[i]);
      s.arm.arm_qpos[i] = m->jnt_qposadr[j];
      s.arm.arm_dof[i] = m->jnt_dofadr[j];
    }
  }
  for (const auto& [adr, c] : joints) {
    const std::string& name = both.qpos_names[c];
    if (StartsWith(name, prefix) && !StartsWith(name, prefix + "doasido_wrist")) s.fingers.emplace_back(adr, c);
  }
  for (int f = 0; f < static_cast<int>(own.qpos.size()); ++f) s.wrists.push_back(WristPose(own, f));
  return s;
}

// The arm's command at fractional command f, its speed and acceleration by
// central differences over one command (the plan's own finite differences).
struct ArmTarget {
  ArmQ q, v, a;
};
ArmTarget TargetAt(const Plan& plan, double f) {
  const double last = static_cast<double>(plan.arm.size() - 1);
  const auto at = [&](double x) {
    x = std::clamp(x, 0.0, last);
    const size_t i = static_cast<size_t>(x), j = std::min(i + 1, plan.arm.size() - 1);
    return ArmQ((1 - (x - i)) * plan.arm[i] + (x - i) * plan.arm[j]);
  };
  const ArmQ q = at(f);
  return {q, (at(f + 0.5) - at(f - 0.5)) * plan.rate_hz, (at(f + 1) - 2 * q + at(f - 1)) * plan.rate_hz * plan.rate_hz};
}

Pose BodyPose(const mjData* d, int body) {
  const mjtNum* p = d->xpos + 3 * body;
  const mjtNum* o = d->xquat + 4 * body;
  return {Quat(o[0], o[1], o[2], o[3]).normalized(), Vec3(p[0], p[1], p[2])};
}

// The hand's contacts with the object: bodies named with the side's prefix.
int HandContacts(const mjModel* m, const mjData* d, int object_body, const std::string& prefix) {
  int contacts = 0;
  for (int c = 0; c < d->ncon; ++c) {
    const int b1 = m->geom_bodyid[d->contact[c].geom1], b2 = m->geom_bodyid[d->contact[c].geom2];
    const int other = b1 == object_body ? b2 : b2 == object_body ? b1 : -1;
    const char* name = other > 0 ? mj_id2name(m, mjOBJ_BODY, other) : nullptr;
    contacts += name && StartsWith(name, prefix);
  }
  return contacts;
}

// Command k's measurements, per side: its wrist carrier against its wrist
// path, its fingers, its contacts; the object (one for both) against the
// trajectory's.
void Measure(const mjModel* m, mjData* d, const retarget::HandTrajectory& both, int object_qpos, int object_body,
             double s, std::array<Side, 2>& sides) {
  mj_kinematics(m, d);  // the poses of the state reached, not of the step before
  const Pose ref = PoseAt(both.object_poses, both.fps, s);
  const mjtNum* q = d->qpos + object_qpos;
  const Pose sim{Quat(q[3], q[4], q[5], q[6]).normalized(), Vec3(q[0], q[1], q[2])};
  const VectorXd target = RowAt(both.qpos, both.fps, s);
  for (Side& side : sides) {
    ReplayReport& r = side.report;
    r.object_position_error.push_back((sim.t - ref.t).norm());
    r.object_rotation_error.push_back(RotationAngle(sim.q, ref.q));
    const Pose carrier = BodyPose(d, side.arm.wrist_body), wrist = PoseAt(side.wrists, both.fps, s);
    r.wrist_position_error.push_back((carrier.t - wrist.t).norm());
    r.wrist_rotation_error.push_back(RotationAngle(carrier.q, wrist.q));
    double finger = 0;
    for (const auto& [adr, c] : side.fingers) finger += std::abs(d->qpos[adr] - target[c]);
    r.finger_error.push_back(side.fingers.empty() ? 0 : finger / side.fingers.size());
    r.hand_contacts.push_back(HandContacts(m, d, object_body, side.prefix));
  }
}

}  // namespace

void ReplayBimanualPlan(BimanualPlan& plan, const retarget::HandTrajectory& both,
                        const retarget::Embodiment& left_hand, const retarget::Embodiment& right_hand,
                        const std::string& scene_xml, const std::filesystem::path& scene_dir, double servo_omega,
                        ReplayMount mount) {
  if (both.object_poses.empty() || scene_xml.empty() || plan.right.arm.empty()) return;
  const auto [left, right] = retarget::SplitBimanualTrajectory(both);
  const retarget::ModelPtr model = TwoSideModel(plan, left_hand, right_hand, mount, scene_xml, scene_dir);
  const mjModel* m = model.get();
  const int object_body = mj_name2id(m, mjOBJ_BODY, "object");
  if (object_body < 0 || m->body_jntnum[object_body] == 0 || m->jnt_type[m->body_jntadr[object_body]] != mjJNT_FREE) {
    return;
  }
  const int object_qpos = m->jnt_qposadr[m->body_jntadr[object_body]];
  const std::vector<std::pair<int, int>> joints = TrajectoryJoints(m, both);
  std::array<Side, 2> sides{MakeSide(m, plan.left, retarget::kLeftPrefix, mount, joints, both, left),
                            MakeSide(m, plan.right, retarget::kRightPrefix, mount, joints, both, right)};
  const HandDrive drive = MatchActuators(m, joints, both);
  const std::vector<double>& source = plan.right.source_times;
  const size_t count = plan.right.arm.size();
  retarget::DataPtr data = retarget::MakeData(m);
  mjData* d = data.get();
  std::vector<mjtNum> mass(m->nv * m->nv);
  // Command f's drive: each arm (set at the start, servoed after), the
  // hands' actuators from the trajectory at the command's trajectory time.
  const auto drive_at = [&](double f, bool start) {
    f = std::clamp(f, 0.0, static_cast<double>(count - 1));
    for (Side& side : sides) {
      if (mount != ReplayMount::kArm) break;
      const ArmTarget t = TargetAt(*side.plan, f);
      if (start || servo_omega <= 0) {
        for (int n = 0; n < 6; ++n) {
          d->qpos[side.arm.arm_qpos[n]] = t.q[n];
          d->qvel[side.arm.arm_dof[n]] = start ? 0 : t.v[n];
        }
      } else {
        ServoArm(m, d, side.arm, t.q, t.v, t.a, servo_omega, mass);
      }
    }
    const size_t i = static_cast<size_t>(f), j = std::min(i + 1, count - 1);
    const double s = (1 - (f - i)) * source[i] + (f - i) * source[j];
    DriveHand(drive, both, s, d);
  };
  drive_at(0, true);
  const VectorXd first = RowAt(both.qpos, both.fps, source[0]);
  for (const auto& [adr, c] : joints) d->qpos[adr] = first[c];
  mj_forward(m, d);
  const size_t path_begin = plan.right.lead_in, path_end = count - plan.right.lead_out;
  size_t k = 0;
  for (long step = 0; k < count; ++step) {
    const double t = step * m->opt.timestep;
    for (; k < count && plan.right.times[k] <= t + 1e-9; ++k) {
      if (k >= path_begin && k < path_end) Measure(m, d, both, object_qpos, object_body, source[k], sides);
    }
    if (k >= count) break;
    drive_at(t * plan.right.rate_hz, false);
    mj_step(m, d);
  }
  const int reference = both.metrics.is_object() && both.metrics.contains(retarget::kMetricSuccess)
                            ? static_cast<int>(both.metrics.at(retarget::kMetricSuccess).get<bool>()) : -1;
  for (Side& side : sides) {
    side.report.reference_success = reference;
    Summarise(side.report);
  }
  plan.left.replay = std::move(sides[0].report);
  plan.right.replay = std::move(sides[1].report);
}

}  // namespace doasido::deploy
