#include "cli/worker.h"

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

#include "cli/stage_registry.h"
#include "core/permanent_error.h"
#include "core/log.h"
#include "core/progress.h"
#include "db/database.h"

namespace doasido::cli {
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

std::string ClipLabel(const ClipContext& context) {
  return context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                          : context.clip.external_id;
}

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
    const auto start = std::chrono::steady_clock::now();
    std::string error;
    bool permanent = false;  // a retry cannot fix it: fail now
    StageResult result;
    std::string label = std::to_string(claim->clip_id);
    try {
      ClipContext context = db.LoadContext(claim->clip_id, claim->stage);
      label = ClipLabel(context);
      std::filesystem::create_directories(context.artifact_dir);
      result = stages.at(claim->stage)->Run(context);
    } catch (const PermanentError& e) {
      error = e.what();
      permanent = true;
    } catch (const Error& e) {
      error = e.what();
    } catch (const std::exception& e) {
      error = std::string("unexpected: ") + e.what();
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // Record this run and claim the next one in a single commit.
    Database::Transaction tx(db);
    if (!error.empty()) {
      spdlog::warn("{} on clip {} (attempt {}): {}", claim->stage, label, claim->attempts, error);
      db.Fail(*claim, worker, error, permanent ? claim->attempts : options.max_attempts);
      ++stats.failed_attempts;
    } else if (db.Complete(*claim, worker, hashes.at(claim->stage), result, seconds)) {
      ++stats.done;
      spdlog::debug("{} {} -> {} {}", claim->stage, label, ToString(result.verdict),
                    result.reason);
    } else {
      ++stats.lost_leases;
      spdlog::warn("{} on clip {}: lease lost before completion; result dropped", claim->stage,
                   label);
    }
    claim = claim_next();
    tx.Commit();
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
    std::unique_ptr<Progress> progress;
    if (options.progress) progress = std::make_unique<Progress>("work", 0);
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
      if (progress) {
        const auto s = db.Summary();
        progress->SetTotal(static_cast<std::uint64_t>(s.pending + s.running + s.done + s.failed));
        progress->Set(static_cast<std::uint64_t>(s.done + s.failed));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    if (progress) progress->Finish();
  }
  Database db(options.db);
  const auto s = db.Summary();
  spdlog::info("queue: {} done, {} failed, {} pending, {} running", s.done, s.failed, s.pending,
               s.running);
  return 0;
}

}  // namespace doasido::cli
