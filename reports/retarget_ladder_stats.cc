#include "reports/retarget_ladder_stats.h"

#include <algorithm>
#include <map>

#include "robot/trajectory/format.h"

namespace doasido::reports {

namespace rt = retarget;

Json RetargetLadderStats::ToJson() const {
  Json per_rung = Json::array();
  for (const RungStats& r : rungs) {
    per_rung.push_back({{"rung", r.rung},
                        {"ran", r.ran},
                        {"succeeded", r.succeeded},
                        {"kept", r.kept},
                        {"seconds", {{"total", r.seconds.total_s},
                                     {"mean", r.seconds.mean_s},
                                     {"median", r.seconds.median_s},
                                     {"max", r.seconds.max_s}}}});
  }
  return {{"simulated", simulated},
          {"succeeded", succeeded},
          {"not_simulated", not_simulated},
          {"rungs", per_rung}};
}

namespace {

double Number(const Json& m, const std::string& key) {
  return m.contains(key) && m[key].is_number() ? m[key].get<double>() : 0.0;
}

bool True(const Json& m, const std::string& key) {
  return m.contains(key) && m[key].is_boolean() && m[key].get<bool>();
}

}  // namespace

RetargetLadderStats ComputeRetargetLadder(Database& db,
                                          const std::vector<Database::ReportRun>& runs) {
  RetargetLadderStats s;
  std::vector<std::string> order;
  std::map<std::string, RungStats> by_rung;
  std::map<std::string, std::vector<double>> seconds;
  for (const auto& run : runs) {
    if (run.stage != rt::kRetargetStageName || run.state != "done") continue;
    const std::optional<Json> m = db.GetMeasurements(run.clip_id, run.stage);
    if (!m || !m->contains(rt::kMetricSuccess)) {
      ++s.not_simulated;
      continue;
    }
    ++s.simulated;
    if (True(*m, rt::kMetricSuccess)) ++s.succeeded;
    if (!m->contains(rt::kMeasurementRungs) || !(*m)[rt::kMeasurementRungs].is_array()) continue;
    const std::string kept = m->value(rt::kMeasurementRung, std::string());
    for (const Json& name : (*m)[rt::kMeasurementRungs]) {
      if (!name.is_string()) continue;
      const std::string rung = name.get<std::string>();
      if (!by_rung.count(rung)) order.push_back(rung);
      RungStats& r = by_rung[rung];
      r.rung = rung;
      ++r.ran;
      if (True(*m, rt::RungMeasurementKey(rung, rt::kMetricSuccess))) ++r.succeeded;
      if (rung == kept) ++r.kept;
      seconds[rung].push_back(Number(*m, rt::RungMeasurementKey(rung, rt::kRungSeconds)));
    }
  }
  for (const std::string& rung : order) {
    RungStats r = by_rung[rung];
    r.seconds = ComputeDurationStats(seconds[rung]);
    s.rungs.push_back(r);
  }
  return s;
}

}  // namespace doasido::reports
