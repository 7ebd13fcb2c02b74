#include "cli/worker_options.h"

#include <memory>

#include "cli/option_checks.h"
#include "core/progress.h"

namespace doasido::cli {

void AddWorkerOptions(CLI::App& cmd, WorkerOptions& opt) {
  cmd.add_option("--jobs,-j", opt.jobs, "Worker processes")
      ->capture_default_str()
      ->check(FiniteRange(1, kMaxJobs));
  cmd.add_option("--stages", opt.stages, "Only these stages, comma-separated, e.g. probe,shot_boundary (default: the whole pipeline)")
      ->delimiter(',')
      ->allow_extra_args(false);  // the lists after it stay positionals
  cmd.add_option("--lease", opt.lease_s,
                 "Seconds a claim is held without a heartbeat before another worker may take it")
      ->capture_default_str()
      ->check(FiniteRange(kMinLeaseSeconds, 7 * 24 * 3600));
  cmd.add_option("--max-attempts", opt.max_attempts,
                 "Attempts per stage run before it is marked failed")
      ->capture_default_str()
      ->check(FiniteRange(1, 1000));
  cmd.add_option("--poll", opt.poll_s, "Seconds to wait when there is nothing to claim")
      ->capture_default_str()
      ->check(FiniteRange(0.01, 3600));
}

WorkerOptions FinishWorkerOptions(WorkerOptions opt, const DbOptions& db) {
  opt.db = db.db;
  opt.config = LoadConfig(db);
  if (Progress::Interactive() || opt.jobs > 1) {
    // Created on first use, in the supervising process only.
    auto bar = std::make_shared<std::unique_ptr<Progress>>();
    opt.progress = [bar](std::int64_t finished, std::int64_t total) {
      if (!*bar) *bar = std::make_unique<Progress>("work", 0);
      (*bar)->SetTotal(static_cast<std::uint64_t>(total));
      (*bar)->Set(static_cast<std::uint64_t>(finished));
    };
    opt.progress_done = [bar] {
      if (*bar) (*bar)->Finish();
    };
  }
  return opt;
}

}  // namespace doasido::cli
