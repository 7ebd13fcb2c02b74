#include "reports/run_stats.h"

#include <algorithm>
#include <cmath>

namespace doasido::reports {

DurationStats ComputeDurationStats(std::vector<double> seconds) {
  DurationStats d;
  d.count = static_cast<std::int64_t>(seconds.size());
  if (seconds.empty()) return d;
  std::sort(seconds.begin(), seconds.end());
  for (double s : seconds) d.total_s += s;
  const size_t n = seconds.size();
  d.mean_s = d.total_s / static_cast<double>(n);
  d.median_s = n % 2 ? seconds[n / 2] : 0.5 * (seconds[n / 2 - 1] + seconds[n / 2]);
  const size_t rank = static_cast<size_t>(std::ceil(0.95 * static_cast<double>(n)));
  d.p95_s = seconds[std::clamp<size_t>(rank, 1, n) - 1];
  d.max_s = seconds.back();
  return d;
}

std::vector<StageRunStats> ComputeRunStats(const std::vector<std::string>& order,
                                           const std::vector<Database::ReportRun>& runs,
                                           const std::vector<Database::EventCount>& events,
                                           const std::vector<Database::EventRow>& error_events,
                                           int max_failures) {
  std::vector<StageRunStats> out;
  std::map<std::string, size_t> index;
  auto slot = [&](const std::string& stage) -> StageRunStats& {
    auto it = index.find(stage);
    if (it != index.end()) return out[it->second];
    index[stage] = out.size();
    out.push_back({.stage = stage});
    return out.back();
  };
  for (const auto& stage : order) slot(stage);
  std::map<std::string, std::vector<double>> durations;
  for (const auto& r : runs) {
    StageRunStats& s = slot(r.stage);
    ++s.runs;
    s.attempts += r.attempts;
    if (r.attempts > 1) ++s.retried_runs;
    if (r.state == "done") {
      ++s.done;
      if (r.duration_s) durations[r.stage].push_back(*r.duration_s);
    } else if (r.state == "failed") {
      ++s.failed;
      if (static_cast<int>(s.failures.size()) < max_failures) {
        s.failures.emplace_back(r.clip_id, r.error);
      }
    } else if (r.state == "running") {
      ++s.running;
    } else {
      ++s.pending;
    }
  }
  for (auto& [stage, values] : durations) slot(stage).duration = ComputeDurationStats(values);
  for (const auto& e : events) {
    if (e.stage.empty() || !index.count(e.stage)) continue;
    StageRunStats& s = slot(e.stage);
    if (e.kind == "claim" || e.kind == "reclaim") s.claims_by_worker[e.worker] += e.count;
    if (e.kind == "retry" || e.kind == "failed") s.failed_attempts += e.count;
  }
  for (const auto& e : error_events) {
    if (e.stage.empty() || !index.count(e.stage)) continue;
    slot(e.stage).errors[e.detail] += 1;
  }
  return out;
}

}  // namespace doasido::reports
