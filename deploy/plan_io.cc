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

// `rate_key`: "speed" or "acceleration" for a joint-limit issue, "" for unreachable.
Json IssuesJson(const std::vector<FrameIssue>& issues, const std::string& rate_key) {
  Json out = Json::array();
  for (const FrameIssue& i : issues) {
    if (!rate_key.empty()) {
      out.push_back({{"frame", i.frame}, {"time", i.time}, {"joint", i.joint}, {rate_key, i.value},
                     {"limit", i.limit}});
    } else {
      out.push_back({{"frame", i.frame}, {"time", i.time}, {"position_error", i.value},
                     {"rotation_error", i.limit}});
    }
  }
  return out;
}

std::vector<FrameIssue> ReadIssues(const Json& j, const std::string& rate_key) {
  std::vector<FrameIssue> out;
  for (const Json& i : j) {
    FrameIssue f{.frame = i.at("frame").get<int>(), .time = i.at("time").get<double>()};
    if (!rate_key.empty()) {
      f.joint = i.at("joint").get<int>();
      f.value = i.at(rate_key).get<double>();
      f.limit = i.at("limit").get<double>();
    } else {
      f.value = i.at("position_error").get<double>();
      f.limit = i.at("rotation_error").get<double>();
    }
    out.push_back(f);
  }
  return out;
}

Json PathDeviationJson(const PathDeviation& d) {
  Json spans = Json::array();
  for (const OffPathSpan& s : d.off_path) {
    spans.push_back({{"first_command", s.first_command}, {"last_command", s.last_command}, {"commands", s.commands},
                     {"start_time", s.start_time}, {"end_time", s.end_time}, {"from_frame", s.from_frame},
                     {"to_frame", s.to_frame}, {"position_deviation", s.position_deviation},
                     {"rotation_deviation", s.rotation_deviation}, {"joint_jump", s.joint_jump}});
  }
  return {{"position_max", d.position_max}, {"rotation_max", d.rotation_max}, {"worst_command", d.worst_command},
          {"position_tolerance", d.position_tolerance}, {"rotation_tolerance", d.rotation_tolerance},
          {kCheckOffPath, spans}};
}

PathDeviation PathDeviationFromJson(const Json& j) {
  PathDeviation d{.checked = true,
                  .position_max = j.at("position_max"),
                  .rotation_max = j.at("rotation_max"),
                  .worst_command = j.at("worst_command"),
                  .position_tolerance = j.at("position_tolerance"),
                  .rotation_tolerance = j.at("rotation_tolerance")};
  for (const Json& s : j.at(kCheckOffPath)) {
    d.off_path.push_back({.first_command = s.at("first_command"), .last_command = s.at("last_command"),
                          .commands = s.at("commands"),
                          .start_time = s.at("start_time"), .end_time = s.at("end_time"),
                          .from_frame = s.at("from_frame"), .to_frame = s.at("to_frame"),
                          .position_deviation = s.at("position_deviation"),
                          .rotation_deviation = s.at("rotation_deviation"), .joint_jump = s.at("joint_jump")});
  }
  return d;
}

}  // namespace

Json PlanToJson(const Plan& plan) {
  Json j;
  j["format"] = kFormat;
  j["version"] = 2;
  j["source"] = plan.source;
  j["embodiment"] = plan.embodiment;
  j["rate_hz"] = plan.rate_hz;
  const Placement& p = plan.placement;
  j["placement"] = {{"yaw", p.yaw}, {"x", p.x}, {"y", p.y},
                    {"world_to_base", PoseJson(p.world_to_base)},
                    {"reachable_fraction", p.reachable_fraction}, {"candidates", p.candidates},
                    {"search_slowdown", p.search_slowdown}, {"manipulability", p.manipulability}};
  j["arm_joints"] = plan.arm_joints;
  j["hand_joints"] = plan.hand_joints;
  j["times"] = plan.times;
  j["source_times"] = plan.source_times;
  j["lead_in"] = plan.lead_in;
  j["lead_out"] = plan.lead_out;
  j["trajectory_duration"] = plan.trajectory_duration;
  j["slowdown"] = plan.slowdown;
  j["wrist_path"] = plan.wrist_path;
  j["wrist_smoothing"] = plan.wrist_smoothing;
  Json arm = Json::array(), hand = Json::array();
  for (const ArmQ& q : plan.arm) arm.push_back(std::vector<double>(q.data(), q.data() + 6));
  for (const Eigen::VectorXd& q : plan.hand) hand.push_back(std::vector<double>(q.data(), q.data() + q.size()));
  j["arm"] = arm;
  j["hand"] = hand;
  j["position_error"] = plan.position_error;
  j["rotation_error"] = plan.rotation_error;
  j[kCheckUnreachable] = IssuesJson(plan.unreachable, "");
  j[kCheckTooFast] = IssuesJson(plan.too_fast, "speed");
  j[kCheckOverAcceleration] = IssuesJson(plan.over_acceleration, "acceleration");
  if (plan.path_deviation.checked) j["path_deviation"] = PathDeviationJson(plan.path_deviation);
  const ReplayReport& r = plan.replay;
  j["replay"] = {{"ran", r.ran},
                 {"object_position_error_mean", r.object_position_error_mean},
                 {"object_position_error_max", r.object_position_error_max},
                 {"object_rotation_error_mean", r.object_rotation_error_mean},
                 {"object_rotation_error_max", r.object_rotation_error_max},
                 {"success", r.success},
                 {"reference_success", r.reference_success},
                 {"object_position_error", r.object_position_error},
                 {"object_rotation_error", r.object_rotation_error},
                 {"wrist_position_error", r.wrist_position_error},
                 {"wrist_rotation_error", r.wrist_rotation_error},
                 {"wrist_position_error_mean", r.wrist_position_error_mean},
                 {"wrist_position_error_max", r.wrist_position_error_max},
                 {"wrist_rotation_error_mean", r.wrist_rotation_error_mean},
                 {"wrist_rotation_error_max", r.wrist_rotation_error_max},
                 {"finger_error", r.finger_error},
                 {"hand_contacts", r.hand_contacts}};
  j["ok"] = plan.ok;
  return j;
}

void WritePlanJson(const Plan& plan, const std::filesystem::path& path) {
  std::ofstream out(path);
  out << PlanToJson(plan).dump(1) << "\n";
  out.close();  // the last bytes reach the disk here: a full disk shows now
  if (!out) throw Error("io", "cannot write plan", {.file = path.string()});
}

namespace {

// PlanFromJson's steps; `field` names the member being read for the error.
Placement PlacementFromJson(const Json& p) {
  Placement placement;
  placement.yaw = p.at("yaw");
  placement.x = p.at("x");
  placement.y = p.at("y");
  const auto w = p.at("world_to_base").get<std::vector<double>>();
  placement.world_to_base = {Quat(w.at(3), w.at(4), w.at(5), w.at(6)), Vec3(w.at(0), w.at(1), w.at(2))};
  placement.reachable_fraction = p.at("reachable_fraction");
  placement.candidates = p.at("candidates");
  placement.search_slowdown = p.value("search_slowdown", 0.0);
  placement.manipulability = p.value("manipulability", 0.0);
  return placement;
}

// The time map and lead moves (version 1: commands at the video's timing).
void ReadTiming(const Json& j, int version, Plan& plan, std::string& field) {
  field = "times";
  plan.times = j.at("times").get<std::vector<double>>();
  if (version < 2) {
    plan.source_times = plan.times;
    return;
  }
  field = "source_times";
  plan.source_times = j.at("source_times").get<std::vector<double>>();
  field = "lead_in";
  plan.lead_in = j.at("lead_in").get<int>();
  plan.lead_out = j.at("lead_out").get<int>();
  field = "slowdown";
  plan.trajectory_duration = j.at("trajectory_duration").get<double>();
  plan.slowdown = j.at("slowdown").get<double>();
  field = "wrist_path";
  plan.wrist_path = j.value("wrist_path", std::string(kWristPathTrajectory));
  field = "wrist_smoothing";
  plan.wrist_smoothing = j.value("wrist_smoothing", WristSmoothingReport{});  // absent before it existed
}

// The arm and hand commands, checked against the timing's length.
void ReadCommands(const Json& j, const std::string& file, Plan& plan, std::string& field) {
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
  if (plan.arm.size() != plan.times.size() || plan.hand.size() != plan.times.size() ||
      plan.source_times.size() != plan.times.size()) {
    throw Error("bad_plan", "times, source_times, arm and hand differ in length", {.file = file, .field = "times"});
  }
  if (plan.lead_in < 0 || plan.lead_out < 0 || plan.lead_in + plan.lead_out > static_cast<int>(plan.times.size())) {
    throw Error("bad_plan", "lead_in + lead_out exceed the commands", {.file = file, .field = "lead_in"});
  }
}

void ReadChecks(const Json& j, int version, Plan& plan, std::string& field) {
  field = "position_error";
  plan.position_error = j.at("position_error").get<std::vector<double>>();
  plan.rotation_error = j.at("rotation_error").get<std::vector<double>>();
  field = kCheckUnreachable;
  plan.unreachable = ReadIssues(j.at(kCheckUnreachable), "");
  field = kCheckTooFast;
  plan.too_fast = ReadIssues(j.at(kCheckTooFast), "speed");
  field = kCheckOverAcceleration;
  if (version >= 2) plan.over_acceleration = ReadIssues(j.at(kCheckOverAcceleration), "acceleration");
  field = "path_deviation";  // absent in files from before the check: unchecked
  if (j.contains("path_deviation")) plan.path_deviation = PathDeviationFromJson(j.at("path_deviation"));
}

// Older files lack the per-command series: they read empty.
ReplayReport ReplayFromJson(const Json& r) {
  return {.ran = r.at("ran"),
          .object_position_error_mean = r.at("object_position_error_mean"),
          .object_position_error_max = r.at("object_position_error_max"),
          .object_rotation_error_mean = r.at("object_rotation_error_mean"),
          .object_rotation_error_max = r.at("object_rotation_error_max"),
          .success = r.at("success"),
          .reference_success = r.value("reference_success", -1),
          .object_position_error = r.value("object_position_error", std::vector<double>{}),
          .object_rotation_error = r.value("object_rotation_error", std::vector<double>{}),
          .wrist_position_error = r.value("wrist_position_error", std::vector<double>{}),
          .wrist_rotation_error = r.value("wrist_rotation_error", std::vector<double>{}),
          .wrist_position_error_mean = r.value("wrist_position_error_mean", 0.0),
          .wrist_position_error_max = r.value("wrist_position_error_max", 0.0),
          .wrist_rotation_error_mean = r.value("wrist_rotation_error_mean", 0.0),
          .wrist_rotation_error_max = r.value("wrist_rotation_error_max", 0.0),
          .finger_error = r.value("finger_error", std::vector<double>{}),
          .hand_contacts = r.value("hand_contacts", std::vector<int>{})};
}

}  // namespace

Plan PlanFromJson(const Json& j, const std::string& file) {
  Plan plan;
  std::string field = "format";
  try {
    if (j.at("format") != kFormat) throw Error("bad_plan", "not a doasido deploy plan", {.file = file, .field = field});
    field = "version";
    const int version = j.at("version").get<int>();
    if (version != 1 && version != 2) throw Error("bad_plan", "unknown plan version", {.file = file, .field = field});
    field = "source";
    plan.source = j.value("source", "");
    plan.embodiment = j.value("embodiment", "");
    field = "rate_hz";
    plan.rate_hz = j.at("rate_hz").get<double>();
    field = "placement";
    plan.placement = PlacementFromJson(j.at("placement"));
    field = "arm_joints";
    plan.arm_joints = j.at("arm_joints").get<std::vector<std::string>>();
    field = "hand_joints";
    plan.hand_joints = j.at("hand_joints").get<std::vector<std::string>>();
    ReadTiming(j, version, plan, field);
    ReadCommands(j, file, plan, field);
    ReadChecks(j, version, plan, field);
    field = "replay";
    plan.replay = ReplayFromJson(j.at("replay"));
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
