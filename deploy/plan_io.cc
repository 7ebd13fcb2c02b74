// WritePlanJson / ReadPlanJson (plan.h).
#include <fstream>

#include "core/error.h"
#include "deploy/plan.h"

namespace doasido::deploy {
namespace {

constexpr const char* kFormat = kPlanFormat;

Json PoseJson(const Pose& p) {
  return Json::array({p.t.x(), p.t.y(), p.t.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()});
}

Json IssuesJson(const std::vector<FrameIssue>& issues, bool speed) {
  Json out = Json::array();
  for (const FrameIssue& i : issues) {
    if (speed) {
      out.push_back({{"frame", i.frame}, {"time", i.time}, {"joint", i.joint}, {"speed", i.value},
                     {"limit", i.limit}});
    } else {
      out.push_back({{"frame", i.frame}, {"time", i.time}, {"position_error", i.value},
                     {"rotation_error", i.limit}});
    }
  }
  return out;
}

std::vector<FrameIssue> ReadIssues(const Json& j, bool speed) {
  std::vector<FrameIssue> out;
  for (const Json& i : j) {
    FrameIssue f{.frame = i.at("frame").get<int>(), .time = i.at("time").get<double>()};
    if (speed) {
      f.joint = i.at("joint").get<int>();
      f.value = i.at("speed").get<double>();
      f.limit = i.at("limit").get<double>();
    } else {
      f.value = i.at("position_error").get<double>();
      f.limit = i.at("rotation_error").get<double>();
    }
    out.push_back(f);
  }
  return out;
}

}  // namespace

Json PlanToJson(const Plan& plan) {
  Json j;
  j["format"] = kFormat;
  j["version"] = 1;
  j["source"] = plan.source;
  j["embodiment"] = plan.embodiment;
  j["rate_hz"] = plan.rate_hz;
  const Placement& p = plan.placement;
  j["placement"] = {{"yaw", p.yaw}, {"x", p.x}, {"y", p.y},
                    {"world_to_base", PoseJson(p.world_to_base)},
                    {"reachable_fraction", p.reachable_fraction}, {"candidates", p.candidates}};
  j["arm_joints"] = plan.arm_joints;
  j["hand_joints"] = plan.hand_joints;
  j["times"] = plan.times;
  Json arm = Json::array(), hand = Json::array();
  for (const ArmQ& q : plan.arm) arm.push_back(std::vector<double>(q.data(), q.data() + 6));
  for (const Eigen::VectorXd& q : plan.hand) hand.push_back(std::vector<double>(q.data(), q.data() + q.size()));
  j["arm"] = arm;
  j["hand"] = hand;
  j["position_error"] = plan.position_error;
  j["rotation_error"] = plan.rotation_error;
  j["unreachable"] = IssuesJson(plan.unreachable, false);
  j["too_fast"] = IssuesJson(plan.too_fast, true);
  const ReplayReport& r = plan.replay;
  j["replay"] = {{"ran", r.ran},
                 {"object_position_error_mean", r.object_position_error_mean},
                 {"object_position_error_max", r.object_position_error_max},
                 {"object_rotation_error_mean", r.object_rotation_error_mean},
                 {"object_rotation_error_max", r.object_rotation_error_max},
                 {"success", r.success}};
  j["ok"] = plan.ok;
  return j;
}

void WritePlanJson(const Plan& plan, const std::filesystem::path& path) {
  std::ofstream out(path);
  out << PlanToJson(plan).dump(1) << "\n";
  if (!out) throw Error("io", "cannot write plan", {.file = path.string()});
}

Plan PlanFromJson(const Json& j, const std::string& file) {
  Plan plan;
  std::string field = "format";
  try {
    if (j.at("format") != kFormat) throw Error("bad_plan", "not a doasido deploy plan", {.file = file, .field = field});
    field = "version";
    if (j.at("version").get<int>() != 1) throw Error("bad_plan", "unknown plan version", {.file = file, .field = field});
    field = "source";
    plan.source = j.value("source", "");
    plan.embodiment = j.value("embodiment", "");
    field = "rate_hz";
    plan.rate_hz = j.at("rate_hz").get<double>();
    field = "placement";
    const Json& p = j.at("placement");
    plan.placement.yaw = p.at("yaw");
    plan.placement.x = p.at("x");
    plan.placement.y = p.at("y");
    const auto w = p.at("world_to_base").get<std::vector<double>>();
    plan.placement.world_to_base = {Quat(w.at(3), w.at(4), w.at(5), w.at(6)), Vec3(w.at(0), w.at(1), w.at(2))};
    plan.placement.reachable_fraction = p.at("reachable_fraction");
    plan.placement.candidates = p.at("candidates");
    field = "arm_joints";
    plan.arm_joints = j.at("arm_joints").get<std::vector<std::string>>();
    field = "hand_joints";
    plan.hand_joints = j.at("hand_joints").get<std::vector<std::string>>();
    field = "times";
    plan.times = j.at("times").get<std::vector<double>>();
    field = "arm";
    for (const auto& q : j.at("arm").get<std::vector<std::vector<double>>>()) {
      if (q.size() != 6) throw Error("bad_plan", "arm command must have 6 joints", {.file = file, .field = field});
      plan.arm.push_back(Eigen::Map<const ArmQ>(q.data()));
    }
    field = "hand";
    for (const auto& q : j.at("hand").get<std::vector<std::vector<double>>>()) {
      if (q.size() != plan.hand_joints.size()) {
        throw Error("bad_plan", "hand command size differs from hand_joints", {.file = file, .field = field});
      }
      plan.hand.push_back(Eigen::Map<const Eigen::VectorXd>(q.data(), q.size()));
    }
    if (plan.arm.size() != plan.times.size() || plan.hand.size() != plan.times.size()) {
      throw Error("bad_plan", "times, arm and hand differ in length", {.file = file, .field = "times"});
    }
    field = "position_error";
    plan.position_error = j.at("position_error").get<std::vector<double>>();
    plan.rotation_error = j.at("rotation_error").get<std::vector<double>>();
    field = "unreachable";
    plan.unreachable = ReadIssues(j.at("unreachable"), false);
    field = "too_fast";
    plan.too_fast = ReadIssues(j.at("too_fast"), true);
    field = "replay";
    const Json& r = j.at("replay");
    plan.replay = {.ran = r.at("ran"),
                   .object_position_error_mean = r.at("object_position_error_mean"),
                   .object_position_error_max = r.at("object_position_error_max"),
                   .object_rotation_error_mean = r.at("object_rotation_error_mean"),
                   .object_rotation_error_max = r.at("object_rotation_error_max"),
                   .success = r.at("success")};
    field = "ok";
    plan.ok = j.at("ok").get<bool>();
  } catch (const nlohmann::json::exception& e) {
    throw Error("bad_plan", std::string("invalid plan JSON: ") + e.what(), {.file = file, .field = field});
  }
  return plan;
}

Json ReadPlanFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw Error("bad_plan", "cannot read plan", {.file = path.string()});
  try {
    return Json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error("bad_plan", std::string("invalid plan JSON: ") + e.what(), {.file = path.string()});
  }
}

Plan ReadPlanJson(const std::filesystem::path& path) { return PlanFromJson(ReadPlanFile(path), path.string()); }

}  // namespace doasido::deploy
