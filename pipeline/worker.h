// Workers: processes that claim stage runs from the queue and run them.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/config.h"
#include "pipeline/stage_run.h"

namespace doasido::pipeline {

// Progress of the queue while workers run: runs finished (done or failed)
// out of all runs. The CLI turns it into its progress bar.
using QueueProgress = std::function<void(std::int64_t finished, std::int64_t total)>;

struct WorkerOptions {
  std::string db;
  Json config = Json::object();
  std::vector<std::string> stages;  // empty: every stage of the pipeline
  int jobs = 1;                     // worker processes
  bool until_empty = false;         // exit when nothing is left to do
  double lease_s = kDefaultLeaseSeconds;  // a dead worker's run is reclaimed after this
  int max_attempts = kDefaultMaxAttempts;
  double poll_s = 0.5;              // idle wait between claims
  // Called about five times a second while the workers run; may be empty.
  QueueProgress progress;
  // Called once when the workers have stopped.
  std::function<void()> progress_done;
};

struct WorkerStats {
  std::int64_t done = 0;
  std::int64_t failed_attempts = 0;
  std::int64_t lost_leases = 0;  // results dropped because the lease had moved on
};

// The exit code of a worker process whose stage run went past its limit
// (stages/stage_timeouts.h): the run is recorded as failed, the
// supervisor starts another worker.
inline constexpr int kTimedOutExitCode = 75;

// One worker loop in this process, with a watch thread that keeps the
// current lease alive and ends the process (kTimedOutExitCode) when a run
// passes its time limit. Returns when the queue is empty (until_empty) or on
// SIGINT/SIGTERM after the current clip.
WorkerStats RunWorkerLoop(const WorkerOptions& options);

// Re-queues runs whose stage parameters changed, then runs options.jobs
// worker processes (children of this one, also for jobs = 1, so a run that
// hangs past its limit cannot take the command with it), restarting any
// that dies from a signal or a timeout while work remains. Clips that fail
// are recorded in the queue, not fatal: returns 0 unless the workers
// themselves could not run.
int RunWorkers(const WorkerOptions& options);

}  // namespace doasido::pipeline
