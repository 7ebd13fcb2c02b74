#include "pipeline/worker.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

#include "core/log.h"
#include "db/database.h"
#include "pipeline/stage_registry.h"

namespace doasido::pipeline {
namespace {

std::atomic<bool> g_stop{false};

void OnStopSignal(int) { g_stop = true; }

std::string WorkerName() {
  char host[256] = {0};
  gethostname(host, sizeof host - 1);
  return std::string(host) + ":" + std::to_string(getpid());
}

// Keeps the lease of the run in progress alive from a second connection, so
// a long stage is not mistaken for a dead worker.
class Heartbeat {
 public:
  Heartbeat(const std::string& db_path, std::string worker, double lease_s)
      : worker_(std::move(worker)), lease_s_(lease_s),
        thread_([this, db_path] { Loop(db_path); }) {}
  ~Heartbeat() {
    {
      std::lock_guard lock(mutex_);
      quit_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  void Set(std::int64_t run_id) { run_id_ = run_id; }

 private:
  void Loop(const std::string& db_path) {
    Database db(db_path);
    std::unique_lock lock(mutex_);
    while (!cv_.wait_for(lock, std::chrono::duration<double>(lease_s_ / 3),
                         [this] { return quit_; })) {
      const std::int64_t run = run_id_;
      if (run != 0) {
        try {
          db.Heartbeat(run, worker_, lease_s_);
        } catch (const std::exception& e) {
          spdlog::warn("heartbeat failed: {}", e.what());
        }
      }
    }
  }

  std::string worker_;
  double lease_s_;
  std::atomic<std::int64_t> run_id_{0};
  std::mutex mutex_;
  std::condition_variable cv_;
  bool quit_ = false;
  std::thread thread_;
};

}  // namespace

WorkerStats RunWorkerLoop(const WorkerOptions& options) {
  Database db(options.db);
  const std::string worker = WorkerName();
  const auto pipeline = db.Pipeline();
  const std::vector<std::string> names = options.stages.empty() ? pipeline : options.stages;
  std::map<std::string, std::unique_ptr<Stage>> stages;
  std::map<std::string, std::string> hashes;
  for (const auto& name : names) {
    stages[name] = MakeStage(name, options.config);
    hashes[name] = ParamHash(stages[name]->Params());
  }
  Heartbeat heartbeat(options.db, worker, options.lease_s);
  WorkerStats stats;
  auto claim_next = [&]() -> std::optional<Claim> {
    if (g_stop) return std::nullopt;
    return db.ClaimNext(worker, names, options.lease_s, options.max_attempts);
  };
  std::optional<Claim> claim = claim_next();
  while (!g_stop) {
    if (!claim) {
      if (options.until_empty) {
        const auto s = db.Summary();
        if (s.pending == 0 && s.running == 0) break;
      }
      std::this_thread::sleep_for(std::chrono::duration<double>(options.poll_s));
      claim = claim_next();
      continue;
    }
    heartbeat.Set(claim->run_id);
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
    heartbeat.Set(claim ? claim->run_id : 0);
  }
  return stats;
}

int RunWorkers(const WorkerOptions& options) {
  {
    Database db(options.db);
    const auto pipeline = db.Pipeline();
    if (pipeline.empty()) {
      throw Error("pipeline", "the database has no pipeline: run `doasido init` first",
                  {.file = options.db});
    }
    for (const auto& name : options.stages.empty() ? pipeline : options.stages) {
      const auto stage = MakeStage(name, options.config);
      const auto changed = db.InvalidateOtherParams(name, ParamHash(stage->Params()));
      if (changed > 0) {
        spdlog::info("{}: parameters changed, {} clips queued again", name, changed);
      }
    }
  }
  struct sigaction action = {};
  action.sa_handler = OnStopSignal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);

  if (options.jobs <= 1 && !options.progress) {
    RunWorkerLoop(options);
  } else {
    std::map<pid_t, int> children;
    auto spawn = [&options, &children](int slot) {
      const pid_t pid = fork();
      if (pid == 0) {
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
    for (int i = 0; i < std::max(1, options.jobs); ++i) spawn(i);
    Database db(options.db);
    while (!children.empty()) {
      int status = 0;
      const pid_t pid = waitpid(-1, &status, WNOHANG);
      if (pid > 0) {
        const int slot = children[pid];
        children.erase(pid);
        if (WIFSIGNALED(status) && !g_stop) {
          const auto s = db.Summary();
          spdlog::warn("worker {} died from signal {}; {}", pid, WTERMSIG(status),
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
  Database db(options.db);
  const auto s = db.Summary();
  spdlog::info("queue: {} done, {} failed, {} pending, {} running", s.done, s.failed, s.pending,
               s.running);
  return 0;
}

}  // namespace doasido::pipeline
