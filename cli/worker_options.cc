#include "cli/worker_options.h"

#include "core/progress.h"

namespace doasido::cli {

void AddWorkerOptions(CLI::App& cmd, WorkerOptions& opt) {
  cmd.add_option("--jobs,-j", opt.jobs, "Worker processes")->capture_default_str();
  cmd.add_option("--stages", opt.stages, "Only these stages (default: the whole pipeline)")
      ->delimiter(',');
  cmd.add_option("--lease", opt.lease_s,
                 "Seconds a claim is held without a heartbeat before another worker may take it")
      ->capture_default_str();
  cmd.add_option("--max-attempts", opt.max_attempts,
                 "Attempts per stage run before it is marked failed")
      ->capture_default_str();
  cmd.add_option("--poll", opt.poll_s, "Seconds to wait when there is nothing to claim")
      ->capture_default_str();
}

WorkerOptions FinishWorkerOptions(WorkerOptions opt, const DbOptions& db) {
  opt.db = db.db;
  opt.config = LoadConfig(db);
  opt.progress = Progress::Interactive() || opt.jobs > 1;
  return opt;
}

}  // namespace doasido::cli
