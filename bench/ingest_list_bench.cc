// Ingest throughput: a generated list of 1,000,000 rows into a fresh
// database, side by side with the sqlite3 shell's bare `.import` of the same
// file (no parsing of spans, no dedupe, no queue rows: the floor of getting
// rows into SQLite). Usage: ingest_list_bench [rows]
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/log.h"
#include "db/database.h"
#include "pipeline/ingest.h"
#include "stages/probe_stage.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  doasido::InitLogging("warn");
  const long rows = argc > 1 ? std::stol(argv[1]) : 1'000'000;
  const fs::path dir = fs::temp_directory_path() / ("doasido-ingest-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path list = dir / "clips.csv";
  {
    std::ofstream out(list);
    out << "video,id,start_frame,end_frame,source,narration\n";
    for (long i = 0; i < rows; ++i) {
      out << "https://example.org/videos/v" << (i % 5000) << ".mp4,clip" << i << ','
          << (i / 5000) * 100 << ',' << (i / 5000) * 100 + 90 << ','
          << (i % 3 == 0 ? "internet" : i % 3 == 1 ? "egocentric" : "generated")
          << ",\"pick up the cup, then put it down\"\n";
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  doasido::Database db(dir / "ingest.db");
  db.SetPipeline({doasido::stages::kProbeStageName});
  const auto summary = doasido::pipeline::IngestList(db, list);
  const double ours = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  const auto t1 = std::chrono::steady_clock::now();
  const std::string cmd = "sqlite3 '" + (dir / "peer.db").string() + "' '.import --csv " +
                          list.string() + " clips'";
  const int rc = std::system(cmd.c_str());
  const double peer = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();

  std::printf("ingest of %ld generated rows (%lld new clips, %zu bad)\n", rows,
              static_cast<long long>(summary.inserted), summary.errors.size());
  std::printf("  doasido ingest        %8.2f s  %10.0f rows/s  (goal: under 60 s)\n", ours,
              rows / ours);
  if (rc == 0) {
    std::printf("  sqlite3 .import (peer) %7.2f s  %10.0f rows/s\n", peer, rows / peer);
    std::printf("  ratio doasido/peer time: %.2fx\n", ours / peer);
  } else {
    std::printf("  sqlite3 shell not available: no peer figure\n");
  }
  fs::remove_all(dir);
  return summary.inserted == rows ? 0 : 1;
}
