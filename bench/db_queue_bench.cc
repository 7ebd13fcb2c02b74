// Queue throughput: claim + complete of the noop stage by 1, 2 and 4 worker
// processes on one database file, side by side with the raw rate of empty
// `BEGIN IMMEDIATE; COMMIT` transactions on the same machine (each claim and
// each completion is one such transaction plus its statements).
// Usage: db_queue_bench [clips]
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "core/log.h"
#include "db/database.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double RawTransactionsPerSecond(const fs::path& path, int n) {
  sqlite3* db = nullptr;
  sqlite3_open(path.c_str(), &db);
  sqlite3_exec(db, "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL; CREATE TABLE t(x)",
               nullptr, nullptr, nullptr);
  const auto t0 = Clock::now();
  for (int i = 0; i < n; ++i) {
    sqlite3_exec(db, "BEGIN IMMEDIATE; INSERT INTO t VALUES (1); COMMIT", nullptr, nullptr,
                 nullptr);
  }
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  sqlite3_close(db);
  return n / s;
}

double ClaimsPerSecond(const fs::path& dir, int workers, int clips) {
  const fs::path path = dir / ("q" + std::to_string(workers) + ".db");
  {
    doasido::Database db(path);
    db.SetPipeline({"noop"});
    doasido::Database::Transaction tx(db);
    const auto video = db.UpsertVideo("https://example.org/v.mp4");
    for (int i = 0; i < clips; ++i) {
      doasido::ClipRecord clip;
      clip.video_id = video;
      clip.start_frame = i;
      clip.end_frame = i + 1;
      db.InsertClip(clip);
    }
    tx.Commit();
  }
  const auto t0 = Clock::now();
  for (int w = 0; w < workers; ++w) {
    if (fork() == 0) {
      doasido::Database db(path);
      const std::string me = "bench:" + std::to_string(getpid());
      doasido::StageResult result;
      // As the worker does: complete a run and claim the next in one commit.
      auto claim = db.ClaimNext(me, {}, 60, 3);
      while (claim) {
        doasido::Database::Transaction tx(db);
        db.Complete(*claim, me, "h", result, 0);
        claim = db.ClaimNext(me, {}, 60, 3);
        tx.Commit();
      }
      _exit(0);
    }
  }
  for (int w = 0; w < workers; ++w) wait(nullptr);
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  doasido::Database db(path);
  if (db.Summary().done != clips) std::printf("  (only %lld done!)\n", (long long)db.Summary().done);
  return clips / s;
}

int main(int argc, char** argv) {
  doasido::InitLogging("warn");
  const int clips = argc > 1 ? std::atoi(argv[1]) : 20000;
  const fs::path dir = fs::temp_directory_path() / ("doasido-queue-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const double raw = RawTransactionsPerSecond(dir / "raw.db", clips);
  std::printf("queue throughput, %d clips, noop stage\n", clips);
  std::printf("  raw SQLite transactions (peer): %9.0f /s\n", raw);
  for (int workers : {1, 2, 4}) {
    const double rate = ClaimsPerSecond(dir, workers, clips);
    std::printf("  %d worker%s claim+complete:     %9.0f /s  (%.2f of raw; goal >= 5000/s with 2)\n",
                workers, workers == 1 ? " " : "s", rate, rate / raw);
  }
  fs::remove_all(dir);
  return 0;
}
