#include "pipeline/worker.h"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <ctime>
#include <map>
#include <set>
#include <memory>
#include <mutex>
#include <opencv2/core/utility.hpp>
#include <thread>

#include "core/child_groups.h"
#include "core/log.h"
#include "core/stage_progress.h"
#include "db/database.h"
#include "stages/stage_registry.h"
#include "stages/stage_timeouts.h"

namespace doasido::pipeline {
namespace {

std::atomic<bool> g_stop{false};

void OnStopSignal(int) { g_stop = true; }

// "host:<pid of the command>/<pid of the worker>": the command is the
// process a person started (and may kill), the worker its child.
std::string WorkerName() { return Database::LeaseOwner(getppid(), getpid()); }

// Watches the run in progress from a second thread with its own
// connection. It renews the run's lease (so a long stage is not mistaken for
// a dead worker) while the run is within its wall-clock limit and, once the
// run has reported progress (core/stage_progress.h), only while that
// progress keeps moving. A run past its limit, or standing still for longer
// than timeouts.no_progress, is failed as a stage timeout and this worker
// process ends, since a hung read or a stuck library call cannot be
// cancelled in place. The supervisor starts another worker
// (kTimedOutExitCode).
class RunWatch {
 public:
  RunWatch(const std::string& db_path, std::string worker, const WorkerOptions& options)
      : worker_(std::move(worker)), options_(options),
        no_progress_s_(stages::NoProgressLimit(options.config)),
        thread_([this, db_path] { Loop(db_path); }) {}
  ~RunWatch() {
    {
      std::lock_guard lock(mutex_);
      quit_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  // Starts watching `claim` (nullopt: nothing is running).
  void Set(const std::optional<Claim>& claim) {
    std::lock_guard lock(mutex_);
    claim_ = claim;
    if (!claim) return;
    started_ = moved_ = std::chrono::steady_clock::now();
    count_at_start_ = count_ = StageProgressCount();
    limit_s_ = stages::StageTimeout(options_.config, claim->stage);
  }

 private:
  using Clock = std::chrono::steady_clock;

  static double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

  // Why the run must stop now, or "" while it may go on.
  std::string Overdue(Clock::time_point now) {
    char text[160];
    if (Seconds(now - started_) > limit_s_) {
      std::snprintf(text, sizeof text, "ran past its limit of %g s (%s.%s in the config)", limit_s_,
                    stages::kTimeoutsSection, claim_->stage.c_str());
      return text;
    }
    const std::uint64_t count = StageProgressCount();
    if (count != count_) {
      count_ = count;
      moved_ = now;
    }
    if (count_ != count_at_start_ && Seconds(now - moved_) > no_progress_s_) {
      std::snprintf(text, sizeof text,
                    "made no progress for %g s after %llu steps (%s.%s in the config)",
                    no_progress_s_, static_cast<unsigned long long>(count_ - count_at_start_),
                    stages::kTimeoutsSection, stages::kNoProgressKey);
      return text;
    }
    return "";
  }

  void Loop(const std::string& db_path) {
    Database db(db_path);
    const auto renew_every = std::chrono::duration<double>(options_.lease_s / 3);
    auto renewed = Clock::now();
    std::unique_lock lock(mutex_);
    while (!cv_.wait_for(lock, std::chrono::milliseconds(200), [this] { return quit_; })) {
      if (!claim_) continue;
      const auto now = Clock::now();
      if (const std::string why = Overdue(now); !why.empty()) {
        TimeOut(db, why);
        continue;
      }
      if (now - renewed < renew_every) continue;
      renewed = now;
      try {
        db.Heartbeat(claim_->run_id, worker_, options_.lease_s);
      } catch (const std::exception& e) {
        spdlog::warn("heartbeat failed: {}", e.what());
      }
    }
  }

  void TimeOut(Database& db, const std::string& why) {
    std::string clip = std::to_string(claim_->clip_id);
    try {
      const std::string external = db.GetClip(claim_->clip_id).external_id;
      if (!external.empty()) clip = external;
    } catch (const std::exception&) {
    }
    const Error error(stages::StageTimeoutCode(claim_->stage), claim_->stage + " " + why, {.clip = clip});
    bool recorded = false;
    try {
      recorded = db.Fail(*claim_, worker_, error.what(),
                         AttemptsAllowed(*claim_, error.code(), options_.max_attempts));
    } catch (const std::exception& e) {
      spdlog::error("cannot record the timeout: {}", e.what());
    }
    claim_.reset();
    if (!recorded) return;  // the run finished (or moved on) meanwhile
    spdlog::error("{}; ending this worker", error.what());
    KillChildGroups();
    std::fflush(nullptr);
    _exit(kTimedOutExitCode);
  }

  std::string worker_;
  const WorkerOptions& options_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool quit_ = false;
  const double no_progress_s_;
  std::optional<Claim> claim_;
  Clock::time_point started_;
  Clock::time_point moved_;  // when the progress count last moved
  std::uint64_t count_at_start_ = 0;
  std::uint64_t count_ = 0;
  double limit_s_ = 0;
  std::thread thread_;
};

}  // namespace

WorkerStats RunWorkerLoop(const WorkerOptions& options) {
  // A worker is one of --jobs processes, each worth a core: OpenCV's own
  // thread pool inside it only hands the small per-frame loops of the
  // analysis back and forth (about 7 % more CPU time there). Stages that
  // want threads say how many in their configs (core/task_pool.h).
  cv::setNumThreads(1);
  Database db(options.db);
  const std::string worker = WorkerName();
  const auto pipeline = db.Pipeline();
  const std::vector<std::string> names = options.stages.empty() ? pipeline : options.stages;
  std::map<std::string, std::unique_ptr<stages::Stage>> stages;
  std::map<std::string, std::string> hashes;
  for (const auto& name : names) {
    stages[name] = stages::MakeStage(name, options.config);
    hashes[name] = stages::ResultHash(*stages[name]);
    stages[name]->Prepare();
  }
  RunWatch watch(options.db, worker, options);
  WorkerStats stats;
  auto claim_next = [&]() -> std::optional<Claim> {
    if (g_stop) return std::nullopt;
    return db.ClaimNext(worker, names, options.lease_s, options.max_attempts);
  };
  std::optional<Claim> claim = claim_next();
  while (!g_stop) {
    watch.Set(claim);
    if (!claim) {
      // Runs of other stages (or waiting for them) are not this worker's.
      if (options.until_empty && db.CountOpen(names) == 0) break;
      std::this_thread::sleep_for(std::chrono::duration<double>(options.poll_s));
      claim = claim_next();
      continue;
    }
    const Claim current = *claim;
    const StageRunReport report =
        RunClaimedStage(db, *stages.at(current.stage), current, worker,
                        hashes.at(current.stage), options.max_attempts,
                        [&] { claim = claim_next(); });  // record and claim in one commit
    switch (report.outcome) {
      case RunOutcome::kDone: ++stats.done; break;
      case RunOutcome::kFailed: ++stats.failed_attempts; break;
      case RunOutcome::kLeaseLost: ++stats.lost_leases; break;
    }
  }
  return stats;
}

namespace {

// Refuses a merged shard or a database without a pipeline, and queues again
// the runs of stages whose parameters changed (saying how many).
void PrepareQueue(const WorkerOptions& options) {
  Database db(options.db);
  db.RefuseMergedShard();
  const auto pipeline = db.Pipeline();
  if (pipeline.empty()) {
    throw Error("pipeline", "the database has no pipeline: run `doasido init` first",
                {.file = options.db});
  }
  for (const auto& name : options.stages.empty() ? pipeline : options.stages) {
    const auto stage = stages::MakeStage(name, options.config);
    std::int64_t downstream = 0;
    const auto changed = db.InvalidateOtherParams(name, stages::ResultHash(*stage), &downstream);
    if (changed > 0) {
      std::printf("%s: parameters changed, %lld clips queued again, and %lld later runs of "
                  "them\n", name.c_str(), static_cast<long long>(changed),
                  static_cast<long long>(downstream));
    }
  }
}

// What the supervisor says about leases that are not its workers': a dead
// worker's run on this machine is taken over at once (Database::
// ExpireDeadLeases), and a run another live process holds is named once
// (clip, stage, holder, until when) so a wait is never silent.
class LeaseWatch {
 public:
  explicit LeaseWatch(std::vector<std::string> stages) : stages_(std::move(stages)) {}
  void Check(Database& db) {
    const auto now = std::chrono::steady_clock::now();
    if (now < next_) return;
    next_ = now + std::chrono::seconds(1);
    for (const Database::Lease& l : db.ExpireDeadLeases()) {
      spdlog::warn("taking over clip {}'s {} run {}: its worker {} is gone (its lease ran until {})",
                   l.clip_id, l.stage, l.run_id, l.owner, Utc(l.expires));
    }
    const std::string ours = Database::LeaseOwner(getpid(), 0);
    const std::string mine = ours.substr(0, ours.rfind('/') + 1);
    for (const Database::Lease& l : db.LiveLeases(stages_)) {
      if (l.owner.compare(0, mine.size(), mine) == 0) continue;  // one of our workers
      if (!told_.insert({l.run_id, l.owner}).second) continue;
      spdlog::warn("waiting for clip {}'s {} run {}: leased by {} until {} (another live worker; "
                   "taken over when the lease ends)",
                   l.clip_id, l.stage, l.run_id, l.owner, Utc(l.expires));
    }
  }

 private:
  static std::string Utc(double seconds) {
    const std::time_t t = static_cast<std::time_t>(seconds);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &tm);
    return text;
  }
  std::vector<std::string> stages_;
  std::set<std::pair<std::int64_t, std::string>> told_;
  std::chrono::steady_clock::time_point next_{};
};

// Runs options.jobs worker processes until they have all ended, starting
// another in place of one killed by a signal or by its stage timeout while
// work is left, and reports progress meanwhile.
void SuperviseWorkers(const WorkerOptions& options) {
  std::map<pid_t, int> children;
  const pid_t parent = getpid();
  auto spawn = [&options, &children, parent](int slot) {
    const pid_t pid = fork();
    if (pid == 0) {
      // A worker does not outlive its command, even one killed with SIGKILL.
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(0);  // the command died before the line above
      int code = 0;
      try {
        RunWorkerLoop(options);
      } catch (const std::exception& e) {
        spdlog::error("worker: {}", e.what());
        code = 1;
      }
      _exit(code);
    }
    if (pid < 0) throw Error("worker", "fork failed");
    children[pid] = slot;
  };
  for (int i = 0; i < options.jobs; ++i) spawn(i);
  Database db(options.db);
  LeaseWatch leases(options.stages);
  while (!children.empty()) {
    leases.Check(db);
    int status = 0;
    const pid_t pid = waitpid(-1, &status, WNOHANG);
    if (pid > 0) {
      const int slot = children[pid];
      children.erase(pid);
      const bool timed_out = WIFEXITED(status) && WEXITSTATUS(status) == kTimedOutExitCode;
      if ((WIFSIGNALED(status) || timed_out) && !g_stop) {
        const auto s = db.Summary(options.stages);
        const std::string why = timed_out ? std::string("ended after a stage timeout")
                                          : "died from signal " + std::to_string(WTERMSIG(status));
        spdlog::warn("worker {} {}; {}", pid, why,
                     s.pending + s.running > 0 ? "starting another" : "no work left");
        if (s.pending + s.running > 0) spawn(slot);
      }
      continue;
    }
    if (g_stop) {
      for (const auto& [child, slot] : children) kill(child, SIGTERM);
    }
    if (options.progress) {
      const auto s = db.Summary();
      options.progress(s.done + s.failed, s.pending + s.running + s.done + s.failed);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  if (options.progress_done) options.progress_done();
}

}  // namespace

int RunWorkers(const WorkerOptions& options) {
  PrepareQueue(options);
  struct sigaction action = {};
  action.sa_handler = OnStopSignal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  SuperviseWorkers(options);
  Database db(options.db);
  const auto s = db.Summary();
  spdlog::info("queue: {} done, {} failed, {} pending, {} running", s.done, s.failed, s.pending,
               s.running);
  return 0;
}

}  // namespace doasido::pipeline
