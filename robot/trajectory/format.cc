#include "robot/trajectory/format.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"

namespace doasido::retarget {

std::string TrajectoryStageOf(const std::vector<std::string>& pipeline) {
  for (const char* stage : kTrajectoryStages) {
    if (std::find(pipeline.begin(), pipeline.end(), stage) != pipeline.end()) return stage;
  }
  return "";
}

bool IsTrajectoryStage(const std::string& stage) {
  return std::find(kTrajectoryStages.begin(), kTrajectoryStages.end(), stage) != kTrajectoryStages.end();
}

FingertipErrorStats SummarizeFingertipError(const std::vector<double>& error) {
  std::vector<double> v;
  for (double e : error) {
    if (std::isfinite(e)) v.push_back(e);
  }
  FingertipErrorStats stats;
  stats.frames = static_cast<int>(v.size());
  if (v.empty()) {
    stats.p95 = std::nan("");
    return stats;
  }
  double sum = 0;
  for (double e : v) sum += e;
  stats.mean = sum / static_cast<double>(v.size());
  std::sort(v.begin(), v.end());
  stats.p95 = v[std::min(v.size() - 1, static_cast<size_t>(0.95 * (v.size() - 1) + 0.5))];
  return stats;
}

void WriteTrajectoryJson(const HandTrajectory& t, const std::filesystem::path& path) {
  Json j;
  j["embodiment"] = t.embodiment;
  j["fps"] = t.fps;
  j["scale"] = t.scale;
  j["qpos_names"] = t.qpos_names;
  j["qpos"] = Json::array();
  for (const auto& q : t.qpos) j["qpos"].push_back(std::vector<double>(q.data(), q.data() + q.size()));
  j["valid"] = t.valid;
  j["fingertip_error"] = Json::array();
  for (double e : t.fingertip_error) j["fingertip_error"].push_back(std::isfinite(e) ? Json(e) : Json());
  j["object_poses"] = Json::array();
  for (const Pose& p : t.object_poses) {
    j["object_poses"].push_back({p.t.x(), p.t.y(), p.t.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()});
  }
  if (!t.reference_keypoints.empty()) {
    j["reference_keypoints"] = Json::array();
    for (const Keypoints21& k : t.reference_keypoints) {
      j["reference_keypoints"].push_back(k.allFinite() ? Json(std::vector<double>(k.data(), k.data() + 63))
                                                       : Json());
    }
  }
  if (!t.ctrl.empty()) {
    j["ctrl_names"] = t.ctrl_names;
    j["ctrl"] = Json::array();
    for (const auto& c : t.ctrl) j["ctrl"].push_back(std::vector<double>(c.data(), c.data() + c.size()));
  }
  if (!t.metrics.empty()) j["metrics"] = t.metrics;
  std::ofstream out(path);
  out << j.dump(1);
  out.close();  // the last bytes reach the disk here: a full disk shows now
  if (!out) throw Error("io", "cannot write trajectory", {.file = path.string()});
}

HandTrajectory ReadTrajectoryJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw Error("bad_trajectory", "cannot read", {.file = path.string()});
  HandTrajectory t;
  try {
    const Json j = Json::parse(in);
    t.embodiment = j.at("embodiment").get<std::string>();
    t.fps = j.at("fps").get<double>();
    t.scale = j.at("scale").get<double>();
    t.qpos_names = j.at("qpos_names").get<std::vector<std::string>>();
    for (const auto& row : j.at("qpos")) {
      const auto v = row.get<std::vector<double>>();
      t.qpos.push_back(Eigen::Map<const Eigen::VectorXd>(v.data(), v.size()));
    }
    t.valid = j.at("valid").get<std::vector<bool>>();
    for (const auto& e : j.at("fingertip_error")) {
      t.fingertip_error.push_back(e.is_null() ? std::nan("") : e.get<double>());
    }
    for (const auto& p : j.at("object_poses")) {
      const auto v = p.get<std::vector<double>>();
      if (v.size() != 7) throw Error("bad_trajectory", "object pose needs 7 numbers",
                                     {.file = path.string(), .field = "object_poses"});
      t.object_poses.push_back({Quat(v[3], v[4], v[5], v[6]), Vec3(v[0], v[1], v[2])});
    }
    if (j.contains("reference_keypoints")) {
      for (const auto& row : j.at("reference_keypoints")) {
        const auto v = row.is_null() ? std::vector<double>(63, std::nan("")) : row.get<std::vector<double>>();
        if (v.size() != 63) throw Error("bad_trajectory", "a reference keypoint row needs 63 numbers",
                                        {.file = path.string(), .field = "reference_keypoints"});
        t.reference_keypoints.push_back(Eigen::Map<const Keypoints21>(v.data()));
      }
    }
    if (j.contains("ctrl")) {
      t.ctrl_names = j.at("ctrl_names").get<std::vector<std::string>>();
      for (const auto& row : j.at("ctrl")) {
        const auto v = row.get<std::vector<double>>();
        t.ctrl.push_back(Eigen::Map<const Eigen::VectorXd>(v.data(), v.size()));
      }
    }
    if (j.contains("metrics")) t.metrics = j.at("metrics");
  } catch (const nlohmann::json::exception& e) {
    throw Error("bad_trajectory", e.what(), {.file = path.string()});
  }
  return t;
}

void WriteTrajectoryCsv(const HandTrajectory& t, const std::filesystem::path& path) {
  std::vector<std::string> header = {"frame", "time", "valid", "fingertip_error"};
  header.insert(header.end(), t.qpos_names.begin(), t.qpos_names.end());
  const bool object = !t.object_poses.empty();
  if (object) {
    header.insert(header.end(),
                  {"obj_tx", "obj_ty", "obj_tz", "obj_qw", "obj_qx", "obj_qy", "obj_qz"});
  }
  std::ofstream out(path);
  out << CsvLine(header);
  std::ostringstream number;
  number.precision(9);
  const auto text = [&number](double v) {
    number.str("");
    number << v;
    return number.str();
  };
  for (size_t f = 0; f < t.qpos.size(); ++f) {
    const double error = t.fingertip_error[f];
    std::vector<std::string> row = {std::to_string(f), text(f / t.fps), t.valid[f] ? "1" : "0",
                                    std::isfinite(error) ? text(error) : ""};
    for (int k = 0; k < t.qpos[f].size(); ++k) row.push_back(text(t.qpos[f][k]));
    if (object && f < t.object_poses.size()) {
      const Pose& p = t.object_poses[f];
      for (double v : {p.t.x(), p.t.y(), p.t.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()}) {
        row.push_back(text(v));
      }
    }
    out << CsvLine(row);
  }
  out.close();
  if (!out) throw Error("io", "cannot write trajectory", {.file = path.string()});
}

std::vector<Keypoints21> ReadKeypointCsv(const std::filesystem::path& path) {
  CsvReader reader = CsvReader::Open(path, "bad_keypoints");
  const std::vector<std::string> header = reader.Header();
  if (header.empty() || header[0] != "k0_x") {
    reader.Fail(reader.header_line(), "", "header must start with k0_x,k0_y,k0_z");
  }
  std::vector<Keypoints21> out;
  CsvRecord record;
  while (reader.Next(record)) {
    if (!record.error.empty()) reader.Fail(record.line, "", record.error);
    if (record.Blank()) continue;
    std::vector<double> v;
    for (const std::string& cell : record.fields) {
      try {
        v.push_back(std::stod(cell));
      } catch (const std::exception&) {
        reader.Fail(record.line, "column " + std::to_string(v.size() + 1),
                    "not a number: '" + cell + "'");
      }
    }
    if (v.size() != 63) {
      reader.Fail(record.line, "", "expected 63 values, got " + std::to_string(v.size()));
    }
    for (double x : v) {
      if (!std::isfinite(x)) reader.Fail(record.line, "", "NaN or infinite coordinate");
    }
    out.push_back(Eigen::Map<const Keypoints21>(v.data()));
  }
  return out;
}

HandTrajectory CombineBimanualTrajectories(const HandTrajectory& left, const HandTrajectory& right) {
  HandTrajectory out = right;
  out.embodiment = left.embodiment + kBimanualSeparator + right.embodiment;
  out.qpos_names.clear();
  for (const std::string& n : left.qpos_names) out.qpos_names.push_back(kLeftPrefix + n);
  for (const std::string& n : right.qpos_names) out.qpos_names.push_back(kRightPrefix + n);
  for (size_t t = 0; t < out.qpos.size(); ++t) {
    Eigen::VectorXd q(left.qpos[t].size() + right.qpos[t].size());
    q << left.qpos[t], right.qpos[t];
    out.qpos[t] = q;
    out.valid[t] = left.valid[t] || right.valid[t];
  }
  return out;
}

std::pair<HandTrajectory, HandTrajectory> SplitBimanualTrajectory(const HandTrajectory& both) {
  const size_t plus = both.embodiment.find(kBimanualSeparator);
  if (plus == std::string::npos) {
    throw Error("bad_trajectory", "not a two-hand trajectory (embodiment '" + both.embodiment + "')",
                {.field = "embodiment"});
  }
  HandTrajectory hands[2];
  const std::string prefixes[2] = {kLeftPrefix, kRightPrefix};
  for (int h = 0; h < 2; ++h) {
    HandTrajectory& t = hands[h];
    t = both;
    t.embodiment = h == 0 ? both.embodiment.substr(0, plus) : both.embodiment.substr(plus + 1);
    const auto pick = [&](const std::vector<std::string>& names, std::vector<std::string>& kept) {
      std::vector<int> columns;
      kept.clear();
      for (size_t i = 0; i < names.size(); ++i) {
        if (names[i].rfind(prefixes[h], 0) != 0) continue;
        columns.push_back(static_cast<int>(i));
        kept.push_back(names[i].substr(prefixes[h].size()));
      }
      return columns;
    };
    const std::vector<int> q = pick(both.qpos_names, t.qpos_names);
    const std::vector<int> u = pick(both.ctrl_names, t.ctrl_names);
    if (q.empty()) {
      throw Error("bad_trajectory", "no " + prefixes[h] + " variables in a two-hand trajectory", {.field = "qpos_names"});
    }
    for (size_t f = 0; f < t.qpos.size(); ++f) {
      t.qpos[f] = both.qpos[f](q);
      if (f < t.ctrl.size()) t.ctrl[f] = both.ctrl[f](u);
    }
    if (h == 0) t.reference_keypoints.clear();  // the keypoints recorded are the right hand's
  }
  return {hands[0], hands[1]};
}

}  // namespace doasido::retarget
