// Run statistics per stage: how many runs, how long they took, how many
// attempts, which failed and why, and which workers did them.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "db/database.h"

namespace doasido::reports {

struct DurationStats {
  std::int64_t count = 0;  // runs with a recorded duration
  double total_s = 0, mean_s = 0, median_s = 0, p95_s = 0, max_s = 0;
};

// Mean, median (mean of the two middle values for an even count), p95 by
// nearest rank (the ceil(0.95 n)-th smallest) and maximum; zeros when empty.
DurationStats ComputeDurationStats(std::vector<double> seconds);

struct StageRunStats {
  std::string stage;
  std::int64_t runs = 0;
  std::int64_t done = 0, failed = 0, pending = 0, running = 0;
  DurationStats duration;             // of done runs
  std::int64_t attempts = 0;          // summed over runs
  std::int64_t retried_runs = 0;      // runs that needed more than one attempt
  std::int64_t failed_attempts = 0;   // 'retry' and 'failed' events
  // The first few failed runs: (clip id, error text).
  std::vector<std::pair<ClipId, std::string>> failures;
  // Distinct error texts of failed attempts (runs that later succeeded
  // included) -> how often.
  std::map<std::string, std::int64_t> errors;
  std::map<std::string, std::int64_t> claims_by_worker;  // 'claim'/'reclaim' events
};

// `order` gives the stages (others with runs follow); `max_failures` caps
// StageRunStats::failures; `error_events` are 'retry'/'failed' events.
std::vector<StageRunStats> ComputeRunStats(const std::vector<std::string>& order,
                                           const std::vector<Database::ReportRun>& runs,
                                           const std::vector<Database::EventCount>& events,
                                           const std::vector<Database::EventRow>& error_events,
                                           int max_failures);

}  // namespace doasido::reports
