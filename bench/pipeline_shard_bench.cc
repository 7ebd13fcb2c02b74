// Shards: what splitting and merging cost, against the work they carry.
//
//   pipeline_shard_bench [merge_clips] [pipeline_clips] [width height frames]
//
// 1. Merge throughput: a shard of `merge_clips` clips (default 100000) with
//    10 stages' results per clip (10 runs, 10 measurements, 10 verdicts,
//    2 detections: 1M measurement rows, 3.2M rows in all) folded into its parent, rows/s,
//    next to a plain `INSERT INTO ... SELECT` of the same tables between the
//    same two files (the peer: what copying the rows costs at all).
// 2. Overhead: `pipeline_clips` synthetic clips (default 200; 160 x 120 px,
//    60 frames unless given, where fixed costs weigh most; `doasido
//    synth`'s own default is 640 x 480, 90 frames) through the
//    default pipeline with one `doasido run --jobs 2`, and the same clips
//    sharded 4 ways, each shard run with --jobs 2 one after the other, and
//    merged. Overhead = (shard + merge) / (sum of the shard runs). Slurm
//    itself adds its scheduling latency per task (tests/cli_slurm_test.cc
//    runs the real thing), which this bench leaves out.
#include <sqlite3.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "db/database.h"
#include "pipeline/shard.h"

namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

void Exec(const std::filesystem::path& db, const std::string& sql) {
  sqlite3* raw = nullptr;
  sqlite3_open(db.c_str(), &raw);
  char* error = nullptr;
  if (sqlite3_exec(raw, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    std::fprintf(stderr, "sql: %s\n", error);
    std::exit(1);
  }
  sqlite3_close(raw);
}

double Run(const std::string& command) {
  const auto t = Clock::now();
  if (std::system((command + " > /dev/null 2>&1").c_str()) != 0) {
    std::fprintf(stderr, "failed: %s\n", command.c_str());
    std::exit(1);
  }
  return Since(t);
}

void MergeThroughput(const std::filesystem::path& dir, int clips) {
  using namespace doasido;
  const auto parent_path = dir / "merge/parent.db";
  std::filesystem::create_directories(parent_path.parent_path());
  {
    Database parent(parent_path);
    parent.SetPipeline({"s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9"});
  }
  // Clips straight in SQL: ingest is not what is measured.
  Exec(parent_path,
       "WITH RECURSIVE n(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM n WHERE i < " +
           std::to_string(clips) +
           ") INSERT INTO videos (id, path) SELECT i, 'v' || i || '.mp4' FROM n;"
           "INSERT INTO clips (id, video_id, start_frame, end_frame, created_at)"
           " SELECT id, id, 0, 89, 0 FROM videos;"
           "INSERT INTO stage_runs (clip_id, stage, position, state)"
           " SELECT id, 's0', 0, 'pending' FROM clips;");
  Database parent(parent_path);
  const auto shards = pipeline::ShardQueue(parent, {.shards = 1, .out_dir = dir / "merge/sh"});
  const auto shard = shards.at(0).db;
  // The shard's results: 10 runs, 10 measurements, 10 verdicts, 2 detections per clip.
  Exec(shard,
       "DELETE FROM stage_runs;"
       "INSERT INTO stage_runs (clip_id, stage, position, state, attempts, param_hash, verdict)"
       " SELECT c.id, p.stage, p.position, 'done', 1, 'h' || p.position, 'pass'"
       " FROM clips c, pipeline p;"
       "INSERT INTO measurements SELECT clip_id, stage, param_hash,"
       " '{\"summary\":{\"score\":' || (clip_id % 97) || '}}', 0 FROM stage_runs;"
       "INSERT INTO verdicts (clip_id, stage, verdict, reason, source, param_hash, created_at)"
       " SELECT clip_id, stage, 'pass', '', 'stage', param_hash, 0 FROM stage_runs;"
       "INSERT INTO detections (clip_id, frame, kind, x1, y1, x2, y2, score, contact_state,"
       " hand_side, dx, dy, magnitude, source) SELECT id, f.f, 'hand', 1, 2, 3, 4, 0.9, 3, 1, 0,"
       " 0, 0, 'bench' FROM clips, (SELECT 0 AS f UNION ALL SELECT 1) f;");
  const double rows = 32.0 * clips;

  auto t = Clock::now();
  const auto stats = pipeline::MergeShard(parent, shard);
  const double merge_s = Since(t);

  const auto copy_path = dir / "merge/copy.db";
  std::filesystem::copy_file(parent_path, copy_path);
  t = Clock::now();
  Exec(copy_path, "ATTACH '" + shard.string() + "' AS s; BEGIN;"
                  "DELETE FROM stage_runs; DELETE FROM measurements; DELETE FROM verdicts;"
                  "DELETE FROM detections;"
                  "INSERT INTO stage_runs SELECT * FROM s.stage_runs;"
                  "INSERT INTO measurements SELECT * FROM s.measurements;"
                  "INSERT INTO verdicts SELECT * FROM s.verdicts;"
                  "INSERT INTO detections SELECT * FROM s.detections; COMMIT;");
  const double copy_s = Since(t);
  t = Clock::now();
  const auto again = pipeline::MergeShard(parent, shard);
  const double again_s = Since(t);
  std::printf("merge: %d clips, %.0f rows (%lld clips changed): %.2f s = %.0f rows/s;"
              " plain INSERT..SELECT copy %.2f s = %.0f rows/s; ratio %.2f\n",
              clips, rows, static_cast<long long>(stats.changed_clips), merge_s, rows / merge_s,
              copy_s, rows / copy_s, copy_s / merge_s);
  std::printf("merge again (nothing changes: %lld clips): %.2f s\n",
              static_cast<long long>(again.changed_clips), again_s);
}

struct ClipSize {
  int width = 160, height = 120, frames = 60;
};

void Overhead(const std::filesystem::path& dir, int clips, const ClipSize& size) {
  const std::string bin = DOASIDO_BIN;
  const std::string pool = (dir / "pool").string();
  Run(bin + " synth --out " + pool + " --clips " + std::to_string(clips) +
      " --frames " + std::to_string(size.frames) + " --width " + std::to_string(size.width) +
      " --height " + std::to_string(size.height) + " --seed 9 --no-bundles");
  const std::string single = (dir / "single/d.db").string();
  const std::string parent = (dir / "parent/d.db").string();
  for (const auto& db : {single, parent}) {
    std::filesystem::create_directories(std::filesystem::path(db).parent_path());
    Run(bin + " init --db " + db);
    Run(bin + " ingest --db " + db + " " + pool + "/Annotations");
  }
  const double one = Run(bin + " run --jobs 2 --db " + single);
  const double shard = Run(bin + " shard --shards 4 --db " + parent + " --out " +
                           (dir / "parent/sh").string());
  double runs = 0;
  for (int i = 0; i < 4; ++i) {
    char name[64];
    std::snprintf(name, sizeof name, "parent/sh/shard-%03d/doasido.db", i);
    runs += Run(bin + " run --jobs 2 --db " + (dir / name).string());
  }
  const double merge = Run(bin + " merge --db " + parent + " " + (dir / "parent/sh").string() +
                           "/shard-*/doasido.db");
  std::printf("pipeline on %d clips of %dx%d px, %d frames: one run %.1f s; 4 shards run one after"
              " another %.1f s (ratio %.2f)\n", clips, size.width, size.height, size.frames, one, runs,
              runs / one);
  std::printf("shard %.2f s + merge %.2f s = %.1f%% of the shards' pipeline time (goal < 5%%)\n",
              shard, merge, 100 * (shard + merge) / runs);
}

}  // namespace

int main(int argc, char** argv) {
  const int merge_clips = argc > 1 ? std::atoi(argv[1]) : 100000;
  const int pipeline_clips = argc > 2 ? std::atoi(argv[2]) : 200;
  const auto dir = std::filesystem::temp_directory_path() / "doasido-shard-bench";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  MergeThroughput(dir, merge_clips);
  ClipSize size;
  if (argc > 5) size = {std::atoi(argv[3]), std::atoi(argv[4]), std::atoi(argv[5])};
  if (pipeline_clips > 0) Overhead(dir, pipeline_clips, size);
  std::filesystem::remove_all(dir);
  return 0;
}
