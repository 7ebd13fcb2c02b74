#include "deploy/plan.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include <spdlog/spdlog.h>

#include "core/config_check.h"
#include "core/error.h"
#include "core/progress.h"

namespace doasido::deploy {
namespace {

constexpr const char* kWrist[6] = {"doasido_wrist_x",  "doasido_wrist_y",  "doasido_wrist_z",
                                   "doasido_wrist_rx", "doasido_wrist_ry", "doasido_wrist_rz"};

// Trajectory sampled at a time: wrist pose (world) and the qpos vector.
struct Sample {
  Pose wrist;
  Eigen::VectorXd qpos;
};

Sample SampleAt(const retarget::HandTrajectory& t, double time) {
  const int n = static_cast<int>(t.qpos.size());
  const double f = std::clamp(time * t.fps, 0.0, static_cast<double>(n - 1));
  const int i = std::min(static_cast<int>(f), n - 1);
  const int j = std::min(i + 1, n - 1);
  const double a = f - i;
  const Pose pi = WristPose(t, i), pj = WristPose(t, j);
  return {{pi.q.slerp(a, pj.q), (1 - a) * pi.t + a * pj.t}, (1 - a) * t.qpos[i] + a * t.qpos[j]};
}

Pose PlacementPose(double yaw, double x, double y, const Vec3& centre, double base_height) {
  const Quat r(Eigen::AngleAxisd(yaw, Vec3::UnitZ()));
  return {r, Vec3(x, y, -base_height) - r * Vec3(centre.x(), centre.y(), 0)};
}

ArmQ Home(const PlanConfig& c) { return Eigen::Map<const ArmQ>(c.home.data()); }

Placement SearchPlacement(const std::vector<Pose>& wrists, const PlanConfig& config) {
  const WorkspaceConfig& w = config.workspace;
  Vec3 centre = Vec3::Zero();
  for (const Pose& p : wrists) centre += p.t;
  centre /= static_cast<double>(wrists.size());
  IkConfig ik_config = config.ik;
  ik_config.restarts = w.search_restarts;
  ArmIk ik(ik_config);
  const int frames = std::min<int>(w.search_frames, wrists.size());
  Placement best;
  double best_error = 1e300;
  int best_reached = -1;
  Progress progress("placement", w.yaw_steps * w.offset_steps * w.offset_steps);
  for (int k = 0; k < w.yaw_steps; ++k) {
    // Yaws alternate around the default: 0, +step, -step, +2 step, ...
    const int signed_k = (k + 1) / 2 * (k % 2 ? 1 : -1);
    const double yaw = w.yaw + signed_k * 2 * std::numbers::pi / w.yaw_steps;
    for (int ix = 0; ix < w.offset_steps; ++ix) {
      for (int iy = 0; iy < w.offset_steps; ++iy) {
        const auto offset = [&](int i) {
          return w.offset_steps == 1 ? 0.0 : w.offset_range * (2.0 * i / (w.offset_steps - 1) - 1);
        };
        const double x = w.x + offset(ix), y = w.y + offset(iy);
        const Pose place = PlacementPose(yaw, x, y, centre, w.base_height);
        ArmQ q = Home(config);
        int reached = 0;
        double error = 0;
        for (int s = 0; s < frames; ++s) {
          const size_t f = frames == 1 ? 0 : s * (wrists.size() - 1) / (frames - 1);
          const IkResult r = ik.Solve(place * wrists[f], q);
          reached += r.reached;
          error += r.position_error + ik_config.rot_scale * r.rotation_error;
          if (r.reached) q = r.q;
        }
        ++best.candidates;
        progress.Add();
        if (reached > best_reached || (reached == best_reached && error < best_error - 1e-9)) {
          best_reached = reached;
          best_error = error;
          best.yaw = yaw;
          best.x = x;
          best.y = y;
          best.world_to_base = place;
          best.reachable_fraction = static_cast<double>(reached) / frames;
        }
      }
    }
  }
  progress.Finish();
  return best;
}

void CheckSpeeds(Plan& plan, const ArmLimits& limits) {
  for (size_t k = 1; k < plan.arm.size(); ++k) {
    const double dt = plan.times[k] - plan.times[k - 1];
    int worst = -1;
    double worst_ratio = 1.0, worst_speed = 0;
    for (int j = 0; j < 6; ++j) {
      const double speed = std::abs(plan.arm[k][j] - plan.arm[k - 1][j]) / dt;
      if (speed / limits.max_speed[j] > worst_ratio) {
        worst_ratio = speed / limits.max_speed[j];
        worst = j;
        worst_speed = speed;
      }
    }
    if (worst >= 0) {
      plan.too_fast.push_back({.frame = static_cast<int>(k), .time = plan.times[k],
                               .value = worst_speed, .limit = limits.max_speed[worst],
                               .joint = worst});
    }
  }
}

}  // namespace

void CheckConfig(const WorkspaceConfig& c, const std::string& section) {
  RequireInRange(section, "x", c.x, -2, 2);
  RequireInRange(section, "y", c.y, -2, 2);
  RequireInRange(section, "yaw", c.yaw, -10, 10);
  RequireInRange(section, "base_height", c.base_height, -2, 2);
  RequireInRange(section, "yaw_steps", c.yaw_steps, 1, 360);
  RequireInRange(section, "offset_range", c.offset_range, 0, 1);
  RequireInRange(section, "offset_steps", c.offset_steps, 1, 21);
  RequireInRange(section, "search_frames", c.search_frames, 1, 1000);
  RequireInRange(section, "search_restarts", c.search_restarts, 0, 100);
}

void CheckConfig(const PlanConfig& c, const std::string& section) {
  RequireInRange(section, "rate_hz", c.rate_hz, 1, 1000);
  CheckConfig(c.workspace, section + ".workspace");
  CheckConfig(c.ik, section + ".ik");
}

Pose WristPose(const retarget::HandTrajectory& t, int frame) {
  int idx[6];
  for (int i = 0; i < 6; ++i) {
    const auto it = std::find(t.qpos_names.begin(), t.qpos_names.end(), kWrist[i]);
    if (it == t.qpos_names.end()) {
      throw Error("bad_trajectory", std::string("trajectory has no floating wrist joint ") + kWrist[i],
                  {.field = "qpos_names"});
    }
    idx[i] = static_cast<int>(it - t.qpos_names.begin());
  }
  const Eigen::VectorXd& q = t.qpos.at(frame);
  const Quat r = Eigen::AngleAxisd(q[idx[3]], Vec3::UnitX()) *
                 Eigen::AngleAxisd(q[idx[4]], Vec3::UnitY()) *
                 Eigen::AngleAxisd(q[idx[5]], Vec3::UnitZ());
  return {r, Vec3(q[idx[0]], q[idx[1]], q[idx[2]])};
}

Pose PlacementPose(double yaw, double x, double y, const std::vector<Pose>& wrists, double base_height) {
  Vec3 centre = Vec3::Zero();
  for (const Pose& p : wrists) centre += p.t;
  centre /= static_cast<double>(std::max<size_t>(1, wrists.size()));
  return PlacementPose(yaw, x, y, centre, base_height);
}

Plan MakePlan(const retarget::HandTrajectory& trajectory, const retarget::Embodiment& embodiment,
              const PlanConfig& config, const Placement* placement) {
  CheckConfig(config, "deploy");
  if (trajectory.qpos.empty() || !(trajectory.fps > 0)) {
    throw Error("bad_trajectory", "trajectory has no frames or no frame rate", {.field = "qpos"});
  }
  Plan plan;
  plan.embodiment = embodiment.name;
  plan.rate_hz = config.rate_hz;
  for (const char* n : Ur3eJointNames()) plan.arm_joints.push_back(n);
  const ArmHandModel model = BuildArmHandModel(embodiment, Pose::Identity());
  plan.hand_joints = model.hand_joints;
  std::vector<int> from(plan.hand_joints.size(), -1);
  for (size_t h = 0; h < plan.hand_joints.size(); ++h) {
    const auto it = std::find(trajectory.qpos_names.begin(), trajectory.qpos_names.end(),
                              plan.hand_joints[h]);
    if (it != trajectory.qpos_names.end()) from[h] = static_cast<int>(it - trajectory.qpos_names.begin());
  }

  const double duration = (trajectory.qpos.size() - 1) / trajectory.fps;
  const int commands = static_cast<int>(std::floor(duration * config.rate_hz + 1e-9)) + 1;
  std::vector<Pose> wrists;
  std::vector<Eigen::VectorXd> qpos;
  for (int k = 0; k < commands; ++k) {
    const Sample s = SampleAt(trajectory, k / config.rate_hz);
    plan.times.push_back(k / config.rate_hz);
    wrists.push_back(s.wrist);
    qpos.push_back(s.qpos);
  }
  plan.placement = placement ? *placement : SearchPlacement(wrists, config);

  ArmIk ik(config.ik);
  ArmQ q = Home(config);
  Progress progress("ik", commands);
  for (int k = 0; k < commands; ++k) {
    const IkResult r = ik.Solve(plan.placement.world_to_base * wrists[k], q);
    q = r.q;
    plan.arm.push_back(r.q);
    plan.position_error.push_back(r.position_error);
    plan.rotation_error.push_back(r.rotation_error);
    if (!r.reached) {
      plan.unreachable.push_back({.frame = k, .time = plan.times[k], .value = r.position_error,
                                  .limit = r.rotation_error});
    }
    Eigen::VectorXd hand = Eigen::VectorXd::Zero(plan.hand_joints.size());
    for (size_t h = 0; h < from.size(); ++h) {
      if (from[h] >= 0) hand[h] = qpos[k][from[h]];
    }
    plan.hand.push_back(hand);
    progress.Add();
  }
  progress.Finish();
  CheckSpeeds(plan, ik.limits());
  if (placement) {
    plan.placement.reachable_fraction = 1.0 - static_cast<double>(plan.unreachable.size()) / commands;
    plan.placement.candidates = 1;
  }
  plan.ok = plan.unreachable.empty() && plan.too_fast.empty();
  return plan;
}

void ReplayPlan(Plan& plan, const retarget::HandTrajectory& trajectory,
                const retarget::Embodiment& embodiment, const std::string& scene_xml,
                const std::filesystem::path& scene_dir) {
  if (trajectory.object_poses.empty() || scene_xml.empty() || plan.arm.empty()) return;
  const ArmHandModel model =
      BuildArmHandModel(embodiment, plan.placement.world_to_base.Inverse(), scene_xml, scene_dir);
  if (model.object_qpos < 0) return;
  const mjModel* m = model.model.get();
  retarget::DataPtr data = retarget::MakeData(m);
  mjData* d = data.get();
  // Actuator -> index into plan.hand for the hand's joint-driven actuators.
  std::map<int, int> hand_index;
  for (size_t h = 0; h < model.hand_qpos.size(); ++h) hand_index[model.hand_qpos[h]] = static_cast<int>(h);
  std::vector<std::pair<int, int>> actuators;
  for (int a = 0; a < m->nu; ++a) {
    if (m->actuator_trntype[a] != mjTRN_JOINT) continue;
    const auto it = hand_index.find(m->jnt_qposadr[m->actuator_trnid[2 * a]]);
    if (it != hand_index.end()) actuators.emplace_back(a, it->second);
  }
  const auto command = [&](double t, ArmQ* arm, Eigen::VectorXd* hand) {
    const double f = std::clamp(t * plan.rate_hz, 0.0, static_cast<double>(plan.arm.size() - 1));
    const size_t i = std::min(static_cast<size_t>(f), plan.arm.size() - 1);
    const size_t j = std::min(i + 1, plan.arm.size() - 1);
    const double a = f - i;
    *arm = (1 - a) * plan.arm[i] + a * plan.arm[j];
    *hand = (1 - a) * plan.hand[i] + a * plan.hand[j];
  };
  ArmQ arm, next;
  Eigen::VectorXd hand, next_hand;
  command(0, &arm, &hand);
  for (int i = 0; i < 6; ++i) d->qpos[model.arm_qpos[i]] = arm[i];
  for (size_t h = 0; h < model.hand_qpos.size(); ++h) d->qpos[model.hand_qpos[h]] = hand[h];
  mj_forward(m, d);
  const double dt = m->opt.timestep;
  double pos_sum = 0, rot_sum = 0;
  ReplayReport& r = plan.replay;
  size_t frame = 0;
  const double end = plan.times.back();
  for (double t = 0; frame < plan.times.size(); t += dt) {
    while (frame < plan.times.size() && plan.times[frame] <= t + 1e-9) {
      const Pose ref = trajectory.object_poses[std::min<size_t>(
          std::lround(plan.times[frame] * trajectory.fps), trajectory.object_poses.size() - 1)];
      const mjtNum* q = d->qpos + model.object_qpos;
      const Pose sim{Quat(q[3], q[4], q[5], q[6]).normalized(), Vec3(q[0], q[1], q[2])};
      const double pe = (sim.t - ref.t).norm(), re = RotationAngle(sim.q, ref.q);
      pos_sum += pe;
      rot_sum += re;
      r.object_position_error_max = std::max(r.object_position_error_max, pe);
      r.object_rotation_error_max = std::max(r.object_rotation_error_max, re);
      ++frame;
    }
    if (t > end) break;
    command(t, &arm, &hand);
    command(t + dt, &next, &next_hand);
    for (int i = 0; i < 6; ++i) {
      d->qpos[model.arm_qpos[i]] = arm[i];
      d->qvel[model.arm_dof[i]] = (next[i] - arm[i]) / dt;
    }
    for (const auto& [a, h] : actuators) d->ctrl[a] = hand[h];
    mj_step(m, d);
  }
  r.ran = frame > 0;
  r.object_position_error_mean = frame ? pos_sum / frame : 0;
  r.object_rotation_error_mean = frame ? rot_sum / frame : 0;
  r.success = r.ran && r.object_position_error_mean < 0.10 && r.object_rotation_error_mean < 0.5;
}

}  // namespace doasido::deploy
