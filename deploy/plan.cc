#include "deploy/plan.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "core/config_check.h"
#include "core/error.h"
#include "core/progress.h"
#include "deploy/placement.h"

namespace doasido::deploy {
namespace {

using Eigen::VectorXd;

constexpr const char* kWrist[6] = {"doasido_wrist_x",  "doasido_wrist_y",  "doasido_wrist_z",
                                   "doasido_wrist_rx", "doasido_wrist_ry", "doasido_wrist_rz"};

ArmQ Home(const PlanConfig& c) { return Eigen::Map<const ArmQ>(c.home.data()); }

// The trajectory's qpos at trajectory time s (linear between frames).
VectorXd QposAt(const retarget::HandTrajectory& t, double s) {
  const int n = static_cast<int>(t.qpos.size());
  const double f = std::clamp(s * t.fps, 0.0, static_cast<double>(n - 1));
  const int i = std::min(static_cast<int>(f), n - 1);
  const int j = std::min(i + 1, n - 1);
  const double a = f - i;
  return (1 - a) * t.qpos[i] + a * t.qpos[j];
}

// Step 2's samples per frame interval when it compares a joint path with
// the wrist path (the commands at 50 Hz fall 1-2 times per 30-Hz frame).
constexpr int kSplineSamples = 4;

// Step 2: the arm's IK at every trajectory frame.
struct ArmPath {
  std::vector<Pose> targets;  // the wrist per frame in the arm's base frame
  std::vector<ArmQ> q;
  std::vector<double> position_error, rotation_error;
  std::vector<FrameIssue> unreachable;
};

ArmPath SolveArmPath(const retarget::HandTrajectory& t, const Pose& world_to_base, const PlanConfig& config) {
  ArmIk ik(config.ik);
  ArmPath path;
  const int frames = static_cast<int>(t.qpos.size());
  for (int f = 0; f < frames; ++f) path.targets.push_back(world_to_base * WristPose(t, f));
  Progress progress("ik", frames);
  std::vector<IkResult> solved = ik.SolveChain(path.targets, Home(config));
  const auto deviation = [&](const std::vector<IkResult>& chain) {
    std::vector<ArmQ> q;
    for (const IkResult& r : chain) q.push_back(r.q);
    return JointSplineDeviation(q, path.targets, t.fps, kSplineSamples);
  };
  if (const SplineDeviation warm = deviation(solved); !warm.Within(config.path_check)) {
    std::vector<IkResult> least = ik.LeastMotionPath(path.targets, Home(config));
    const SplineDeviation other = deviation(least);
    if (std::pair(!other.Within(config.path_check), other.position) < std::pair(true, warm.position)) {
      solved = std::move(least);
    }
  }
  for (int f = 0; f < frames; ++f) {
    const IkResult& r = solved[f];
    path.q.push_back(r.q);
    path.position_error.push_back(r.position_error);
    path.rotation_error.push_back(r.rotation_error);
    if (!r.reached) {
      path.unreachable.push_back({.frame = f, .time = f / t.fps, .value = r.position_error,
                                  .limit = r.rotation_error});
    }
    progress.Add();
  }
  progress.Finish();
  return path;
}

// A plan's description and step 2's outcome, before its commands.
Plan StartPlan(const retarget::Embodiment& embodiment, const Placement& placement,
               const WristSmoothingReport& smoothing, const ArmPath& path, double duration, const PlanConfig& config) {
  Plan plan;
  plan.embodiment = embodiment.name;
  plan.rate_hz = config.rate_hz;
  for (const char* n : Ur3eJointNames()) plan.arm_joints.push_back(n);
  plan.hand_joints = BuildArmHandModel(embodiment, Pose::Identity()).hand_joints;
  plan.placement = placement;
  plan.wrist_smoothing = smoothing;
  plan.trajectory_duration = duration;
  plan.position_error = path.position_error;
  plan.rotation_error = path.rotation_error;
  plan.unreachable = path.unreachable;
  return plan;
}

// The trajectory's qpos index of each of the plan's hand joints (-1: absent).
std::vector<int> HandSource(const Plan& plan, const retarget::HandTrajectory& t) {
  std::vector<int> from(plan.hand_joints.size(), -1);
  for (size_t h = 0; h < plan.hand_joints.size(); ++h) {
    const auto it = std::find(t.qpos_names.begin(), t.qpos_names.end(), plan.hand_joints[h]);
    if (it != t.qpos_names.end()) from[h] = static_cast<int>(it - t.qpos_names.begin());
  }
  return from;
}

VectorXd HandAt(const std::vector<int>& from, const retarget::HandTrajectory& t, double s) {
  const VectorXd qpos = QposAt(t, s);
  VectorXd hand = VectorXd::Zero(from.size());
  for (size_t h = 0; h < from.size(); ++h) {
    if (from[h] >= 0) hand[h] = qpos[from[h]];
  }
  return hand;
}

// The lead moves' command intervals (the longest arm's on one clock):
// home to the approach pose, the approach down onto the first frame, the
// lead-out back home.
struct Leads {
  int to_approach = 0, approach = 0, out = 0;
};

// Step 3's commands for arm `index` (joints 6 index .. of the shared
// path): lead-in (home to `above`, then down to the first frame), the path
// at the time map's s, lead-out.
void FillCommands(Plan& plan, const retarget::HandTrajectory& t, const JointSpline& path, int index,
                  const TimeMap& map, const Leads& leads, const ArmQ& above, const ArmQ& home) {
  const std::vector<int> from = HandSource(plan, t);
  plan.times.clear();
  plan.source_times.clear();
  plan.arm.clear();
  plan.hand.clear();
  const auto push = [&](const ArmQ& q, double s) {
    plan.times.push_back(plan.times.size() / plan.rate_hz);
    plan.source_times.push_back(s);
    plan.arm.push_back(q);
    plan.hand.push_back(HandAt(from, t, s));
  };
  const ArmQ first = path.Value(map.s.front()).segment<6>(6 * index);
  const ArmQ last = path.Value(map.s.back()).segment<6>(6 * index);
  for (int k = 0; k < leads.to_approach; ++k) {
    push(RestToRestAt(home, above, double(k) / leads.to_approach), map.s.front());
  }
  for (int k = 0; k < leads.approach; ++k) {
    push(RestToRestAt(above, first, double(k) / leads.approach), map.s.front());
  }
  for (double s : map.s) push(path.Value(s).segment<6>(6 * index), s);
  for (int k = 1; k <= leads.out; ++k) push(RestToRestAt(last, home, double(k) / leads.out), map.s.back());
  plan.lead_in = leads.to_approach + leads.approach;
  plan.lead_out = leads.out;
  plan.slowdown = map.slowdown;
}

// Where the lead-in's approach starts: the first frame's wrist raised by
// config.approach_height (the arm's IK, seeded with the first frame's
// joints), so the hand comes down onto the first frame instead of sweeping
// in from home through what it is about to touch (a clip may start with
// the hand at or on the object). The first frame's joints when the height
// is 0 or IK misses the raised pose.
ArmQ ApproachPose(const retarget::HandTrajectory& t, const Placement& placement, const ArmQ& first,
                  const PlanConfig& config) {
  if (!(config.approach_height > 0)) return first;
  Pose wrist = WristPose(t, 0);
  wrist.t.z() += config.approach_height;
  const IkResult r = ArmIk(config.ik).Solve(placement.world_to_base * wrist, first);
  return r.reached ? r.q : first;
}

// Step 4's speed and acceleration checks.
void CheckLimits(Plan& plan, const ArmLimits& limits) {
  plan.too_fast.clear();
  plan.over_acceleration.clear();
  const std::vector<VectorXd> q(plan.arm.begin(), plan.arm.end());
  const VectorXd vmax = Eigen::Map<const VectorXd>(limits.max_speed.data(), 6);
  const VectorXd amax = Eigen::Map<const VectorXd>(limits.max_acceleration.data(), 6);
  for (const LimitExcess& e : CheckCommandLimits(q, plan.rate_hz, vmax, amax)) {
    const FrameIssue issue{.frame = e.command, .time = plan.times[e.command], .value = e.value,
                           .limit = e.limit, .joint = e.joint};
    (e.acceleration ? plan.over_acceleration : plan.too_fast).push_back(issue);
  }
}

// "frames 3-7, 12, 20-31" (at most `most` runs, then "...").
std::string FrameRuns(const std::vector<FrameIssue>& issues, size_t most = 5) {
  std::string out;
  size_t runs = 0;
  for (size_t i = 0; i < issues.size(); ++i) {
    size_t j = i;
    while (j + 1 < issues.size() && issues[j + 1].frame == issues[j].frame + 1) ++j;
    if (runs++ == most) return out + ", ...";
    out += (out.empty() ? "" : ", ") + std::to_string(issues[i].frame) +
           (j > i ? "-" + std::to_string(issues[j].frame) : "");
    i = j;
  }
  return out;
}

// Error(kUnfollowablePath) for a re-timing that gave up (TimeMap::exceeded):
// the arm whose joint holds the path back, where, and what its IK found there.
Error UnfollowablePath(const TimeMap& map, const std::vector<ArmPath>& paths, double fps,
                       const std::vector<const retarget::Embodiment*>& embodiments,
                       const std::vector<Placement>& placements, const PlanConfig& config) {
  const size_t arm = static_cast<size_t>(std::max(map.slowest_joint, 0)) / 6;
  const ArmPath& path = paths[arm];
  const int frames = static_cast<int>(path.q.size());
  const int frame = std::clamp(static_cast<int>(std::floor(map.slowest_s * fps)), 0, std::max(frames - 2, 0));
  const double step = frames > 1 ? (path.q[frame + 1] - path.q[frame]).cwiseAbs().maxCoeff() : 0.0;
  const Placement& p = placements[arm];
  char text[512];
  std::snprintf(text, sizeof(text),
                "the %s arm (arm %zu of %zu) cannot follow its joint path within %.1fx the trajectory's duration "
                "(it would take %.1fx): slowest between frames %d and %d (t = %.2f s), %s held back, a joint "
                "moving %.2f rad from one frame to the next; %zu of its %d frames out of reach%s%s; placement "
                "x %.3f m, y %.3f m, yaw %.3f rad",
                embodiments[arm]->name.c_str(), arm + 1, paths.size(), config.time_scaling.max_slowdown,
                map.slowdown, frame, frame + 1, frame / fps, Ur3eJointNames()[map.slowest_joint % 6], step,
                path.unreachable.size(), frames, path.unreachable.empty() ? "" : ": frames ",
                FrameRuns(path.unreachable).c_str(), p.x, p.y, p.yaw);
  return Error(kUnfollowablePath, text, {.field = "deploy.time_scaling.max_slowdown"});
}

// The commands of `plan` that fail a check.
size_t FailingCount(const Plan& plan) {
  return plan.unreachable.size() + plan.too_fast.size() + plan.over_acceleration.size() +
         plan.path_deviation.OffPathCommands();
}

// MakePlan at the search's best placement; when that plan leaves the wrist
// path between frames (a branch jump the IK could not avoid there), at the
// next ones too (workspace.fallback_placements), keeping the plan with the
// fewest failing commands. A plan that does not leave the path keeps the
// best placement: the replay's outcome at it is not traded for another's.
Plan PlanAtRankedPlacements(const retarget::HandTrajectory& trajectory, const retarget::Embodiment& embodiment,
                            const PlanConfig& config, const std::vector<Pose>& wrists) {
  const std::vector<Placement> ranked = RankPlacements(wrists, trajectory.fps, config);
  std::optional<Plan> best;
  std::optional<Error> unfollowable;
  for (size_t i = 0; i < ranked.size() && i <= static_cast<size_t>(config.workspace.fallback_placements); ++i) {
    try {
      Plan plan = MakePlansOnOneClock({&trajectory}, {&embodiment}, {ranked[i]}, config)[0];
      if (!best || FailingCount(plan) < FailingCount(*best)) best = std::move(plan);
    } catch (const Error& e) {
      if (e.code() != kUnfollowablePath) throw;
      if (!unfollowable) unfollowable = e;
    }
    if (best && best->path_deviation.off_path.empty()) break;
  }
  if (!best) throw *unfollowable;
  return *best;
}

void RequireTrajectory(const retarget::HandTrajectory& t) {
  if (t.qpos.empty() || !(t.fps > 0)) {
    throw Error("bad_trajectory", "trajectory has no frames or no frame rate", {.field = "qpos"});
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
  RequireInRange(section, "manipulability_floor", c.manipulability_floor, 0, 1);
  RequireInRange(section, "fallback_placements", c.fallback_placements, 0, 100);
}

void CheckConfig(const PlanConfig& c, const std::string& section) {
  RequireInRange(section, "rate_hz", c.rate_hz, 1, 1000);
  CheckConfig(c.workspace, section + ".workspace");
  CheckConfig(c.ik, section + ".ik");
  CheckConfig(c.time_scaling, section + ".time_scaling");
  RequireInRange(section, "servo_omega", c.servo_omega, 0, 1000);
  RequireInRange(section, "approach_height", c.approach_height, 0, 0.5);
  RequireInRange(section, "approach_speed", c.approach_speed, 0.005, 1);
  RequireInRange(section, "follow_rounds", c.follow_rounds, 0, 5);
  RequireInRange(section, "follow_smoothing", c.follow_smoothing, 0, 2);
  CheckConfig(c.wrist_smoothing, section + ".wrist_smoothing");
  CheckConfig(c.path_check, section + ".path_check");
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
  const Quat r(Eigen::AngleAxisd(yaw, Vec3::UnitZ()));
  return {r, Vec3(x, y, -base_height) - r * Vec3(centre.x(), centre.y(), 0)};
}

std::vector<Plan> MakePlansOnOneClock(const std::vector<const retarget::HandTrajectory*>& given,
                                      const std::vector<const retarget::Embodiment*>& embodiments,
                                      const std::vector<Placement>& placements, const PlanConfig& config) {
  CheckConfig(config, "deploy");
  const size_t arms = given.size();
  // Step 0: the arms follow the smoothed wrist paths.
  std::vector<retarget::HandTrajectory> smoothed(arms);
  std::vector<WristSmoothingReport> smoothing(arms);
  std::vector<const retarget::HandTrajectory*> trajectories;
  for (size_t a = 0; a < arms; ++a) {
    RequireTrajectory(*given[a]);
    smoothed[a] = SmoothWrist(*given[a], config.wrist_smoothing, &smoothing[a]);
    trajectories.push_back(&smoothed[a]);
  }
  for (const auto* t : trajectories) {
    RequireTrajectory(*t);
    if (t->qpos.size() != trajectories[0]->qpos.size() || t->fps != trajectories[0]->fps) {
      throw Error("bad_trajectory", "trajectories on one clock differ in frames or frame rate", {.field = "qpos"});
    }
  }
  const retarget::HandTrajectory& first = *trajectories[0];
  const int frames = static_cast<int>(first.qpos.size());
  std::vector<Plan> plans(arms);
  std::vector<ArmPath> paths;
  for (size_t a = 0; a < arms; ++a) {
    paths.push_back(SolveArmPath(*trajectories[a], placements[a].world_to_base, config));
    plans[a] = StartPlan(*embodiments[a], placements[a], smoothing[a], paths[a], (frames - 1) / first.fps, config);
  }
  // One joint path over every arm's joints: the re-timing's slowest joint
  // of any arm sets the pace for all.
  std::vector<double> knots;
  std::vector<VectorXd> values;
  for (int f = 0; f < frames; ++f) {
    knots.push_back(f / first.fps);
    VectorXd q(6 * arms);
    for (size_t a = 0; a < arms; ++a) q.segment<6>(6 * a) = paths[a].q[f];
    values.push_back(q);
  }
  const JointSpline path(knots, values);
  const ArmLimits limits = Ur3eLimits();
  const VectorXd vmax1 = Eigen::Map<const VectorXd>(limits.max_speed.data(), 6);
  const VectorXd amax1 = Eigen::Map<const VectorXd>(limits.max_acceleration.data(), 6);
  const VectorXd vmax = vmax1.replicate(arms, 1), amax = amax1.replicate(arms, 1);
  const ArmQ home = Home(config);
  std::vector<ArmQ> above;
  for (size_t a = 0; a < arms; ++a) above.push_back(ApproachPose(*trajectories[a], placements[a], paths[a].q[0], config));
  // The approach's duration at config.approach_speed, at least.
  const int approach_min =
      config.approach_height > 0 ? static_cast<int>(std::ceil(config.approach_height / config.approach_speed * config.rate_hz)) : 0;
  double margin = config.time_scaling.margin;
  for (int attempt = 0; attempt < config.time_scaling.attempts; ++attempt, margin *= 0.8) {
    const TimeMap map = RetimePath(path, vmax, amax, config.rate_hz, config.time_scaling, margin);
    if (map.exceeded) throw UnfollowablePath(map, paths, first.fps, embodiments, placements, config);
    Leads leads;
    for (size_t a = 0; a < arms && config.lead_in; ++a) {
      const VectorXd start = path.Value(map.s.front()).segment<6>(6 * a);
      leads.to_approach = std::max(leads.to_approach, RestToRestIntervals(home, above[a], vmax1, amax1, config.rate_hz, margin));
      const int down = RestToRestIntervals(above[a], start, vmax1, amax1, config.rate_hz, margin);
      leads.approach = std::max(leads.approach, down > 0 ? std::max(down, approach_min) : 0);
    }
    for (size_t a = 0; a < arms && config.lead_out; ++a) {
      const VectorXd end = path.Value(map.s.back()).segment<6>(6 * a);
      leads.out = std::max(leads.out, RestToRestIntervals(end, home, vmax1, amax1, config.rate_hz, margin));
    }
    bool within = true;
    for (size_t a = 0; a < arms; ++a) {
      FillCommands(plans[a], *trajectories[a], path, static_cast<int>(a), map, leads, above[a], home);
      CheckLimits(plans[a], limits);
      within = within && plans[a].too_fast.empty() && plans[a].over_acceleration.empty();
    }
    if (within) break;
  }
  for (size_t a = 0; a < arms; ++a) {
    Plan& plan = plans[a];
    plan.path_deviation = CheckPathDeviation(plan, paths[a].targets, first.fps, paths[a].q, config.path_check);
    plan.ok = plan.unreachable.empty() && plan.too_fast.empty() && plan.over_acceleration.empty() &&
              plan.path_deviation.off_path.empty();
  }
  return plans;
}

Plan MakePlan(const retarget::HandTrajectory& trajectory, const retarget::Embodiment& embodiment,
              const PlanConfig& config, const Placement* placement) {
  CheckConfig(config, "deploy");
  RequireTrajectory(trajectory);
  std::vector<Pose> wrists;  // the smoothed path's, which the arm will follow (MakePlansOnOneClock)
  const retarget::HandTrajectory smoothed = SmoothWrist(trajectory, config.wrist_smoothing, nullptr);
  for (int f = 0; f < static_cast<int>(smoothed.qpos.size()); ++f) wrists.push_back(WristPose(smoothed, f));
  if (!placement) return PlanAtRankedPlacements(trajectory, embodiment, config, wrists);
  Plan plan = MakePlansOnOneClock({&trajectory}, {&embodiment}, {*placement}, config)[0];
  plan.placement.reachable_fraction = 1.0 - static_cast<double>(plan.unreachable.size()) / wrists.size();
  plan.placement.candidates = 1;
  return plan;
}

FollowedPlan PlanOnFloatingWrist(const Plan& plan, const retarget::HandTrajectory& trajectory,
                                 const retarget::Embodiment& embodiment, const PlanConfig& config,
                                 const std::string& scene_xml, const std::filesystem::path& scene_dir) {
  FollowedPlan out{plan, trajectory};
  if (trajectory.object_poses.empty() || scene_xml.empty()) return out;
  for (int round = 0; round < config.follow_rounds; ++round) {
    out.trajectory = FloatingWristTrajectory(out.plan, trajectory, embodiment, scene_xml, scene_dir,
                                             config.servo_omega, config.follow_smoothing);
    out.plan = MakePlan(out.trajectory, embodiment, config, &plan.placement);
    // The search's record stays; the reach is the new path's.
    const double reached = out.plan.placement.reachable_fraction;
    out.plan.placement = plan.placement;
    out.plan.placement.reachable_fraction = reached;
    out.plan.source = plan.source;
    out.plan.wrist_path = kWristPathFloating;
  }
  return out;
}

}  // namespace doasido::deploy
