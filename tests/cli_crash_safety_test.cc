// Crash safety of the queue: worker processes killed with SIGKILL at random
// while they work; at the end every clip is done exactly once.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <random>
#include <thread>

#include "db/database.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::DoasidoBin;
using testing::RunDoasido;
using testing::TempDir;
using testing::WriteFile;

pid_t StartWorker(const std::string& db, const std::string& config) {
  const pid_t pid = fork();
  if (pid == 0) {
    // Quiet: the test reads the database, not the logs.
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, STDERR_FILENO);
    dup2(null, STDOUT_FILENO);
    execl(DoasidoBin().c_str(), "doasido", "--log-level", "error", "worker", "--db", db.c_str(),
          "--config", config.c_str(), "--until-empty", "--lease", "1", "--max-attempts", "20",
          "--poll", "0.05", static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

TEST(CrashSafety, KilledWorkersLoseAndDuplicateNothing) {
  constexpr int kClips = 2000;
  constexpr int kWorkers = 4;
  constexpr int kMinKills = 20;
  TempDir dir;
  const std::string db = (dir / "q.db").string();
  std::string list = "video,id,start_frame,end_frame\n";
  for (int i = 0; i < kClips; ++i) {
    list += "https://example.org/v" + std::to_string(i % 7) + ".mp4,c" + std::to_string(i) + "," +
            std::to_string(i) + "," + std::to_string(i + 10) + "\n";
  }
  WriteFile(dir / "clips.csv", list);
  WriteFile(dir / "work.toml", "[noop]\nwork_ms = 15\n");
  ASSERT_EQ(RunDoasido({"init", "--db", db, "--pipeline", "noop"}).exit_code, 0);
  const auto ingest = RunDoasido({"ingest", "--db", db, (dir / "clips.csv").string()});
  ASSERT_EQ(ingest.exit_code, 0) << ingest.err;

  std::vector<pid_t> workers;
  for (int i = 0; i < kWorkers; ++i) workers.push_back(StartWorker(db, (dir / "work.toml").string()));
  std::mt19937 rng(7);
  int kills = 0;
  Database watch(db);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(60 + rng() % 120));
    // Reap workers that finished on their own.
    for (auto& pid : workers) {
      if (pid > 0 && waitpid(pid, nullptr, WNOHANG) == pid) pid = 0;
    }
    workers.erase(std::remove(workers.begin(), workers.end(), 0), workers.end());
    if (workers.empty()) break;
    if (kills >= kMinKills + 10) continue;
    // Kill a worker that holds a lease right now, so the kill lands mid-clip.
    std::vector<size_t> busy;
    for (const auto& run : watch.ListRuns({.state = "running"})) {
      const auto colon = run.lease_owner.rfind(':');
      if (colon == std::string::npos) continue;
      const pid_t owner = std::stoi(run.lease_owner.substr(colon + 1));
      for (size_t i = 0; i < workers.size(); ++i) {
        if (workers[i] == owner) busy.push_back(i);
      }
    }
    if (busy.empty()) continue;
    const size_t victim = busy[rng() % busy.size()];
    kill(workers[victim], SIGKILL);
    waitpid(workers[victim], nullptr, 0);
    ++kills;
    workers[victim] = StartWorker(db, (dir / "work.toml").string());
  }
  for (pid_t pid : workers) {
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
  }
  ASSERT_GE(kills, kMinKills);

  Database check(db);
  const auto summary = check.Summary();
  EXPECT_EQ(summary.done, kClips);
  EXPECT_EQ(summary.pending, 0);
  EXPECT_EQ(summary.running, 0) << "stuck leases";
  EXPECT_EQ(summary.failed, 0);
  const auto done_events = check.DoneEventCounts();
  EXPECT_EQ(done_events.size(), static_cast<size_t>(kClips)) << "a clip was never completed";
  int duplicates = 0;
  for (const auto& [key, n] : done_events) duplicates += n > 1;
  EXPECT_EQ(duplicates, 0) << "a clip was completed twice";
  EXPECT_EQ(check.CountClips(), kClips);
  // The kills did land mid-work: some runs needed a second attempt.
  int retried = 0;
  for (const auto& run : check.ListRuns({})) retried += run.attempts > 1;
  EXPECT_GT(retried, 0);
  std::printf("%d kills, %d runs reclaimed after a kill\n", kills, retried);
}

}  // namespace
}  // namespace doasido
