// Workers: processes that claim stage runs from the queue and run them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"

namespace doasido::cli {

struct WorkerOptions {
  std::string db;
  Json config = Json::object();
  std::vector<std::string> stages;  // empty: every stage of the pipeline
  int jobs = 1;                     // worker processes
  bool until_empty = false;         // exit when nothing is left to do
  double lease_s = 60;              // a dead worker's run is reclaimed after this
  int max_attempts = 3;
  double poll_s = 0.5;              // idle wait between claims
  bool progress = true;
};

struct WorkerStats {
  std::int64_t done = 0;
  std::int64_t failed_attempts = 0;
  std::int64_t lost_leases = 0;  // results dropped because the lease had moved on
};

// One worker loop in this process (with a heartbeat thread keeping the
// current lease alive). Returns when the queue is empty (until_empty) or on
// SIGINT/SIGTERM after the current clip.
WorkerStats RunWorkerLoop(const WorkerOptions& options);

// Re-queues runs whose stage parameters changed, then runs options.jobs
// worker processes, restarting any that dies from a signal while work
// remains. Clips that fail are recorded in the queue, not fatal: returns 0
// unless the workers themselves could not run.
int RunWorkers(const WorkerOptions& options);

}  // namespace doasido::cli
