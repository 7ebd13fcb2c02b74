#include "deploy/bimanual.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <optional>

#include <lcm/lcm-cpp.hpp>

#include "core/config_check.h"
#include "core/error.h"
#include "deploy/lcm_log.h"
#include "doasido_lcm/bimanual_command.hpp"

namespace doasido::deploy {
namespace {

struct Capsule {
  Vec3 a, b;
  double radius = 0;
};

// Least distance between segments p1-q1 and p2-q2 (Ericson, Real-Time
// Collision Detection, 5.1.9).
double SegmentDistance(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  constexpr double kTiny = 1e-18;
  double s = 0, t = 0;
  if (a <= kTiny && e <= kTiny) return r.norm();
  if (a <= kTiny) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kTiny) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > kTiny ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p1 + s * d1) - (p2 + t * d2)).norm();
}

// An arm's links and hand in the world.
std::vector<Capsule> ArmCapsules(const ArmQ& q, const Pose& base, const BimanualConfig& c) {
  const std::array<Vec3, 7> o = DhOrigins(q);
  std::vector<Capsule> out;
  for (int i = 0; i < 6; ++i) out.push_back({base * o[i], base * o[i + 1], Ur3eLinkRadii()[i]});
  const Pose flange = base * DhForwardPose(q);
  out.push_back({flange.t, flange * Vec3(0, 0, c.hand_length), c.hand_radius});
  return out;
}

doasido_lcm::bimanual_command Message(const BimanualPlan& plan, size_t k, int64_t timestamp_us) {
  doasido_lcm::bimanual_command msg;
  msg.timestamp_us = timestamp_us;
  msg.sequence = static_cast<int64_t>(k);
  msg.plan_time = plan.right.times[k];
  for (int i = 0; i < 6; ++i) {
    msg.left_arm_q[i] = plan.left.arm[k][i];
    msg.right_arm_q[i] = plan.right.arm[k][i];
  }
  const Eigen::VectorXd& l = plan.left.hand[k];
  const Eigen::VectorXd& r = plan.right.hand[k];
  msg.num_left_hand = static_cast<int32_t>(l.size());
  msg.left_hand_q.assign(l.data(), l.data() + l.size());
  msg.num_right_hand = static_cast<int32_t>(r.size());
  msg.right_hand_q.assign(r.data(), r.data() + r.size());
  return msg;
}

}  // namespace

void CheckConfig(const BimanualConfig& c, const std::string& section) {
  RequireInRange(section, "base_distance", c.base_distance, 0, 5);  // m
  RequireInRange(section, "clearance", c.clearance, 0, 1);
  RequireInRange(section, "hand_length", c.hand_length, 0, 1);
  RequireInRange(section, "hand_radius", c.hand_radius, 0, 0.5);
  CheckConfig(c.plan, section + ".plan");
}

double ArmArmDistance(const ArmQ& left, const Pose& left_base, const ArmQ& right, const Pose& right_base,
                      const BimanualConfig& config, bool hand_to_hand) {
  const std::vector<Capsule> a = ArmCapsules(left, left_base, config);
  const std::vector<Capsule> b = ArmCapsules(right, right_base, config);
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < a.size(); ++i) {
    for (size_t j = 0; j < b.size(); ++j) {
      if (!hand_to_hand && i + 1 == a.size() && j + 1 == b.size()) continue;  // the hands: last capsules
      best = std::min(best, SegmentDistance(a[i].a, a[i].b, b[j].a, b[j].b) - a[i].radius - b[j].radius);
    }
  }
  return best;
}

namespace {

// The commands of `plan` that fail a check: either arm's unreachable
// frames, limit excesses and commands off the wrist path, and the arm-arm
// collisions.
size_t FailingCount(const BimanualPlan& plan) {
  size_t n = plan.collisions.size();
  for (const Plan* p : {&plan.left, &plan.right}) {
    n += p->unreachable.size() + p->too_fast.size() + p->over_acceleration.size() +
         p->path_deviation.OffPathCommands();
  }
  return n;
}

// Both arms planned with the pair's frame at (x, y) on the table (the
// workspace's yaw), and their arm-arm distances checked.
BimanualPlan PlanPairAt(const retarget::HandTrajectory& left, const retarget::HandTrajectory& right,
                        const retarget::Embodiment& left_hand, const retarget::Embodiment& right_hand,
                        const BimanualConfig& config, double x, double y) {
  std::vector<Pose> wrists;
  Vec3 across = Vec3::Zero();  // from the right wrist to the left, summed over frames
  for (int f = 0; f < static_cast<int>(left.qpos.size()); ++f) {
    wrists.push_back(WristPose(left, f));
    wrists.push_back(WristPose(right, f));
    across += wrists[wrists.size() - 2].t - wrists.back().t;
  }
  // The pair is turned so that the left hand works on the left arm's side
  // (+y of the pair's frame), then by the workspace's yaw.
  const WorkspaceConfig& w = config.plan.workspace;
  const double yaw = w.yaw + std::numbers::pi / 2 - std::atan2(across.y(), across.x());
  const Pose world_to_pair = PlacementPose(yaw, x, y, wrists, w.base_height);
  // p_base = p_pair - (base position in the pair's frame).
  const auto place = [&](double side) {
    Placement p;
    p.yaw = yaw;
    p.x = x;
    p.y = y;
    p.world_to_base = Pose{Quat::Identity(), Vec3(0, -side * config.base_distance / 2, 0)} * world_to_pair;
    return p;
  };
  const Placement left_place = place(+1), right_place = place(-1);
  BimanualPlan out;
  std::vector<Plan> plans =
      MakePlansOnOneClock({&left, &right}, {&left_hand, &right_hand}, {left_place, right_place}, config.plan);
  out.left = std::move(plans[0]);
  out.right = std::move(plans[1]);
  for (Plan* p : {&out.left, &out.right}) {
    p->placement.reachable_fraction = 1.0 - static_cast<double>(p->unreachable.size()) / left.qpos.size();
    p->placement.candidates = 1;
  }
  const Pose left_base = left_place.world_to_base.Inverse(), right_base = right_place.world_to_base.Inverse();
  for (size_t k = 0; k < out.left.arm.size(); ++k) {
    const bool on_path = k >= static_cast<size_t>(out.left.lead_in) && k + out.left.lead_out < out.left.arm.size();
    const double d = ArmArmDistance(out.left.arm[k], left_base, out.right.arm[k], right_base, config, !on_path);
    out.arm_distance.push_back(d);
    if (d < config.clearance) {
      out.collisions.push_back({.frame = static_cast<int>(k), .time = out.left.times[k], .value = d,
                                .limit = config.clearance});
    }
  }
  out.ok = out.left.ok && out.right.ok && out.collisions.empty();
  return out;
}

}  // namespace

BimanualPlan MakeBimanualPlan(const retarget::HandTrajectory& left, const retarget::HandTrajectory& right,
                              const retarget::Embodiment& left_hand, const retarget::Embodiment& right_hand,
                              const BimanualConfig& config) {
  CheckConfig(config, "deploy");
  if (left.qpos.size() != right.qpos.size() || left.fps != right.fps || left.qpos.empty()) {
    throw Error("bad_trajectory",
                "left and right trajectories differ in frames (" + std::to_string(left.qpos.size()) + " and " +
                    std::to_string(right.qpos.size()) + ") or frame rate",
                {.field = "qpos"});
  }
  const WorkspaceConfig& w = config.plan.workspace;
  // A spot where an arm cannot follow its path within the re-timing's
  // bound (far out of reach) fails every command: it is passed over, and
  // when every spot is, the first spot's error names the arm and frames.
  std::optional<Error> unfollowable;
  const auto plan_at = [&](double x, double y) -> std::optional<BimanualPlan> {
    try {
      return PlanPairAt(left, right, left_hand, right_hand, config, x, y);
    } catch (const Error& e) {
      if (e.code() != kUnfollowablePath) throw;
      if (!unfollowable) unfollowable = e;
      return std::nullopt;
    }
  };
  std::optional<BimanualPlan> best = plan_at(w.x, w.y);
  if (best && best->ok) return *best;
  // The default spot fails a check (two forearms crossing where the hands
  // meet, say): the pair's frame moved over the workspace's offset grid,
  // the fewest failing commands kept, then the least slowdown.
  int candidates = 1;
  const auto offset = [&](int i) {
    return w.offset_steps == 1 ? 0.0 : w.offset_range * (2.0 * i / (w.offset_steps - 1) - 1);
  };
  const auto key = [](const BimanualPlan& q) { return std::pair(FailingCount(q), q.right.slowdown); };
  for (int ix = 0; ix < w.offset_steps; ++ix) {
    for (int iy = 0; iy < w.offset_steps; ++iy) {
      if (offset(ix) == 0 && offset(iy) == 0) continue;
      std::optional<BimanualPlan> p = plan_at(w.x + offset(ix), w.y + offset(iy));
      ++candidates;
      if (p && (!best || key(*p) < key(*best))) best = std::move(p);
    }
  }
  if (!best) {
    const std::string others = candidates == 1 ? "" : " (and at the " + std::to_string(candidates - 1) +
                                                          " other spots within " +
                                                          std::to_string(w.offset_range).substr(0, 4) + " m of it)";
    throw Error(kUnfollowablePath, unfollowable->message() + others, {.field = "deploy.workspace"});
  }
  best->left.placement.candidates = best->right.placement.candidates = candidates;
  return *best;
}

StreamResult StreamBimanualPlan(const BimanualPlan& plan, const StreamOptions& options,
                                const std::atomic<bool>& stop) {
  if (!plan.ok) {
    std::string times;
    for (size_t i = 0; i < plan.collisions.size() && i < 5; ++i) {
      times += (i ? ", " : "") + std::to_string(plan.collisions[i].time) + " s";
    }
    throw Error("plan_failed_checks",
                "refusing to stream: " + std::to_string(plan.collisions.size()) + " arm-arm collision commands" +
                    (times.empty() ? "" : " (" + times + (plan.collisions.size() > 5 ? ", ..." : "") + ")") +
                    ", left plan " + (plan.left.ok ? "ok" : "failed") + ", right plan " +
                    (plan.right.ok ? "ok" : "failed"),
                {.field = "ok"});
  }
  RequireEvenlySpaced(plan.left);
  RequireEvenlySpaced(plan.right);
  const double rate = options.rate_hz > 0 ? options.rate_hz : plan.right.rate_hz;
  return StreamEncoded(plan.right.arm.size(), rate, options, stop,
                       [&](size_t k, int64_t t) { return EncodeLcm(Message(plan, k, t)); });
}

void WriteBimanualPlanJson(const BimanualPlan& plan, const BimanualConfig& config,
                           const std::filesystem::path& path) {
  Json collisions = Json::array();
  for (const FrameIssue& c : plan.collisions) {
    collisions.push_back({{"frame", c.frame}, {"time", c.time}, {"distance", c.value}});
  }
  const Json j = {{"format", kBimanualPlanFormat}, {"version", 1},
                  {"base_distance", config.base_distance}, {"clearance", config.clearance},
                  {"left", PlanToJson(plan.left)}, {"right", PlanToJson(plan.right)},
                  {"arm_distance", plan.arm_distance}, {"collisions", collisions}, {"ok", plan.ok}};
  std::ofstream out(path);
  out << j.dump(1) << "\n";
  out.close();  // the last bytes reach the disk here: a full disk shows now
  if (!out) throw Error("io", "cannot write plan", {.file = path.string()});
}

BimanualPlan BimanualPlanFromJson(const Json& j, const std::string& file) {
  BimanualPlan plan;
  std::string field = "format";
  try {
    if (j.at("format") != kBimanualPlanFormat) {
      throw Error("bad_plan", "not a doasido two-arm plan", {.file = file, .field = field});
    }
    field = "version";
    if (j.at("version").get<int>() != 1) throw Error("bad_plan", "unknown plan version", {.file = file, .field = field});
    field = "left";
    plan.left = PlanFromJson(j.at("left"), file);
    field = "right";
    plan.right = PlanFromJson(j.at("right"), file);
    if (plan.left.arm.size() != plan.right.arm.size()) {
      throw Error("bad_plan", "left and right plans differ in length", {.file = file, .field = "left"});
    }
    field = "arm_distance";
    plan.arm_distance = j.at("arm_distance").get<std::vector<double>>();
    field = "collisions";
    const double clearance = j.at("clearance").get<double>();
    for (const Json& c : j.at("collisions")) {
      plan.collisions.push_back({.frame = c.at("frame").get<int>(), .time = c.at("time").get<double>(),
                                 .value = c.at("distance").get<double>(), .limit = clearance});
    }
    field = "ok";
    plan.ok = j.at("ok").get<bool>();
  } catch (const nlohmann::json::exception& e) {
    throw Error("bad_plan", std::string("invalid plan JSON: ") + e.what(), {.file = file, .field = field});
  }
  return plan;
}

std::vector<BimanualRecord> ReadBimanualLog(const std::filesystem::path& path, const std::string& channel) {
  return ReadLcmLog<doasido_lcm::bimanual_command, BimanualRecord>(
      path, channel, "a bimanual_command", [](const lcm::LogEvent& e, const doasido_lcm::bimanual_command& msg) {
        BimanualRecord r{.log_time_us = e.timestamp, .timestamp_us = msg.timestamp_us,
                         .sequence = msg.sequence, .plan_time = msg.plan_time};
        for (int i = 0; i < 6; ++i) {
          r.left_arm[i] = msg.left_arm_q[i];
          r.right_arm[i] = msg.right_arm_q[i];
        }
        r.left_hand = msg.left_hand_q;
        r.right_hand = msg.right_hand_q;
        return r;
      });
}

}  // namespace doasido::deploy
