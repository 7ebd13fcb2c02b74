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
//    synth`'s own default is 640 x 480, 90 frames; rendered once per size
//    and kept in the temporary folder for later runs) through the
//    `filters` pipeline with one `doasido run --jobs 2`, and the same clips
//    sharded 4 ways, each shard run with --jobs 2 one after the other, and
//    merged. Overhead = (shard + merge) / (sum of the shard runs).
// 3. Through Slurm (as root, with Debian's slurm-wlm and munge; then again in
//    three stage groups, the middle one, a light stage, on partition gpu with
//    a GRES): the same clips in a fresh parent, `doasido slurm submit --shards 4
//    --cpus-per-task 1` to a one-node cluster started on loopback
//    (testing/slurm/loopback_cluster.h), timed from the submit command to the
//    merge job's end by polling squeue every 0.2 s, against the one
//    `doasido run` of section 2: total wall time, and what Slurm adds in
//    phases (submit = shard + script + sbatch; the wait for the first task;
//    the array; the merge job's wait for its dependency and its run).
#include <sqlite3.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <string>
#include <thread>

#include "db/database.h"
#include "pipeline/shard.h"
#include "testing/db_dump.h"
#include "testing/slurm/loopback_cluster.h"

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

// Seconds from `t0` at which each phase of a Slurm submission was first seen.
struct SlurmPhases {
  double submitted = 0, first_task = -1, array_done = -1, merge_started = -1, merge_done = -1;
  std::map<std::string, std::pair<double, double>> tasks;  // task id: first and last seen running
};

// Polls squeue until the array `array` and the merge job `merge` have left it.
SlurmPhases WatchSlurm(Clock::time_point t0, const std::string& array, const std::string& merge) {
  SlurmPhases p;
  p.submitted = Since(t0);
  // One line per job or array task: "<id> <state>".
  const auto listed = [](const std::string& queue, const std::string& pattern) {
    return std::regex_search(queue, std::regex("(^|\n)" + pattern));
  };
  const std::regex running_task("(^|\n)" + array + "_(\\d+) RUNNING");
  while (p.merge_done < 0) {
    const std::string queue = doasido::testing::Shell("squeue -h -o '%i %T'");
    const double now = Since(t0);
    for (auto it = std::sregex_iterator(queue.begin(), queue.end(), running_task);
         it != std::sregex_iterator(); ++it) {
      p.tasks.try_emplace((*it)[2], now, now).first->second.second = now;
    }
    if (p.first_task < 0 && !p.tasks.empty()) p.first_task = now;
    if (p.array_done < 0 && !listed(queue, array + "_")) p.array_done = now;
    if (p.merge_started < 0 && listed(queue, merge + " RUNNING")) p.merge_started = now;
    if (!listed(queue, merge + " ")) p.merge_done = now;
    if (Since(t0) > 7200) {
      std::fprintf(stderr, "slurm: still running after 2 h\n%s", queue.c_str());
      std::exit(1);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  // A phase shorter than one poll was not seen: it ended with the next one.
  if (p.first_task < 0) p.first_task = p.array_done;
  if (p.merge_started < 0) p.merge_started = p.merge_done;
  return p;
}

// Seconds of stage runs recorded in a database (the pipeline's own work).
double StageSeconds(const std::filesystem::path& db) {
  return std::stod(doasido::testing::QueryRows(
      db, "SELECT COALESCE(SUM(duration_s), 0) FROM stage_runs")[0]);
}

// The same clips in three stage groups (pipeline/slurm_groups.h): the
// pipeline's first three stages, the fourth alone on partition gpu with the
// node's one GRES (so its tasks run one at a time: a light stage there, or
// the GPU queue is what is measured), the rest; timed from the submit
// command until the merge job has left the queue, against the one run and
// the one-group submission.
void ThroughSlurmInGroups(const std::filesystem::path& dir, const std::string& pool,
                          double one_run_s, double one_group_s) {
  const std::string bin = DOASIDO_BIN;
  const std::string parent = (dir / "slurm-groups/d.db").string();
  std::filesystem::create_directories(std::filesystem::path(parent).parent_path());
  Run(bin + " init --pipeline filters --db " + parent);
  Run(bin + " ingest --db " + parent + " " + pool + "/Annotations");
  const auto stages =
      doasido::testing::QueryRows(parent, "SELECT stage FROM pipeline ORDER BY position");
  if (stages.size() < 5) return;
  const std::string groups = " --group '" + stages[0] + ".." + stages[2] + " name=first'" +
                             " --group '" + stages[3] + " name=gpu partition=gpu gpus=1'" +
                             " --group '" + stages[4] + ".." + stages.back() + " name=rest'";
  const auto t0 = Clock::now();
  const std::string out = doasido::testing::Shell(
      bin + " slurm submit --db " + parent + " --shards 4 --cpus-per-task 1 --time 02:00:00" +
      groups);
  std::smatch m;
  if (!std::regex_search(out, m, std::regex("merge job (\\d+)"))) {
    std::fprintf(stderr, "slurm submit: %s\n", out.c_str());
    std::exit(1);
  }
  const double submitted = Since(t0);
  const std::regex merge("(^|\n)" + m[1].str() + " ");
  while (std::regex_search(doasido::testing::Shell("squeue -h -o '%i %T'"), merge)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  const double total = Since(t0);
  const std::string left = doasido::testing::QueryRows(
      parent, "SELECT COUNT(*) FROM stage_runs WHERE state <> 'done'")[0];
  std::printf("through Slurm in 3 stage groups (%s..%s | %s on partition gpu, gres gpu:1 |"
              " %s..%s), 4 shards: %.1f s from submit to merged (submit %.2f s), ratio %.3f to"
              " the one run, %.3f to the one-group submission; stage runs not done: %s\n",
              stages[0].c_str(), stages[2].c_str(), stages[3].c_str(), stages[4].c_str(),
              stages.back().c_str(), total, submitted, total / one_run_s, total / one_group_s,
              left.c_str());
}

void ThroughSlurm(const std::filesystem::path& dir, const std::string& pool, double one_run_s,
                  const std::filesystem::path& one_run_db) {
  const std::string bin = DOASIDO_BIN;
  if (geteuid() != 0 || std::system("command -v slurmctld sbatch munged > /dev/null") != 0) {
    std::printf("slurm: skipped (needs root and Debian's slurm-wlm and munge: scripts/setup.sh)\n");
    return;
  }
  doasido::testing::LoopbackSlurm cluster(dir / "slurm");
  if (!cluster.WaitIdle(60)) {
    std::fprintf(stderr, "slurm: the node did not come up\n%s", cluster.Logs().c_str());
    std::exit(1);
  }
  const std::string parent = (dir / "slurm-parent/d.db").string();
  std::filesystem::create_directories(std::filesystem::path(parent).parent_path());
  Run(bin + " init --pipeline filters --db " + parent);
  Run(bin + " ingest --db " + parent + " " + pool + "/Annotations");
  const auto t0 = Clock::now();
  const std::string out = doasido::testing::Shell(
      bin + " slurm submit --db " + parent + " --shards 4 --cpus-per-task 1 --time 02:00:00");
  std::smatch m;
  if (!std::regex_search(out, m, std::regex("array job (\\d+) .*merge job (\\d+)"))) {
    std::fprintf(stderr, "slurm submit: %s\n", out.c_str());
    std::exit(1);
  }
  const SlurmPhases p = WatchSlurm(t0, m[1], m[2]);
  const std::string left = doasido::testing::QueryRows(
      parent, "SELECT COUNT(*) FROM stage_runs WHERE state <> 'done'")[0];
  const double added = p.first_task + (p.merge_done - p.array_done);
  std::printf("through Slurm (4 array tasks, 1 CPU each, on this %u-CPU node): %.1f s from submit"
              " to merged, against one run's %.1f s (ratio %.3f); stage runs not done in the"
              " parent: %s\n",
              std::thread::hardware_concurrency(), p.merge_done, one_run_s,
              p.merge_done / one_run_s, left.c_str());
  std::printf("  submit (shard + scripts + sbatch) %.2f s | wait for the first task %.2f s |"
              " array %.1f s | merge job: wait %.2f s + run %.2f s\n",
              p.submitted, p.first_task - p.submitted, p.array_done - p.first_task,
              p.merge_started - p.array_done, p.merge_done - p.merge_started);
  std::printf("  submit + first wait + merge job = %.2f s = %.1f%% of one run\n", added,
              100 * added / one_run_s);
  for (const auto& [task, seen] : p.tasks) {
    char name[32];
    std::snprintf(name, sizeof name, "shard-%03d", std::stoi(task));
    const auto shard = std::filesystem::path(parent).parent_path() / "shards" / name / "doasido.db";
    std::printf("  task %s: running %.1f .. %.1f s (%.1f s), its stage runs %.1f s\n",
                task.c_str(), seen.first, seen.second, seen.second - seen.first,
                StageSeconds(shard));
  }
  std::printf("  stage runs: one run %.1f s, the parent after the merge %.1f s\n",
              StageSeconds(one_run_db), StageSeconds(parent));
  ThroughSlurmInGroups(dir, pool, one_run_s, p.merge_done);
}

// The synthetic clips, rendered once per size and kept between runs of the
// bench (rendering 200 clips of 640 x 480 px takes ~10 min on one core;
// `synth` is deterministic for its seed).
std::filesystem::path Pool(int clips, const ClipSize& size) {
  char name[96];
  std::snprintf(name, sizeof name, "doasido-shard-bench-pool-%dx%dx%d-%d", size.width, size.height,
                size.frames, clips);
  const auto pool = std::filesystem::temp_directory_path() / name;
  if (std::filesystem::exists(pool / "complete")) return pool;
  std::filesystem::remove_all(pool);
  Run(std::string(DOASIDO_BIN) + " synth --out " + pool.string() + " --clips " +
      std::to_string(clips) + " --frames " + std::to_string(size.frames) + " --width " +
      std::to_string(size.width) + " --height " + std::to_string(size.height) +
      " --seed 9 --no-bundles");
  std::ofstream(pool / "complete") << "rendered\n";
  return pool;
}

// Returns the one run's wall time.
double Overhead(const std::filesystem::path& dir, int clips, const ClipSize& size) {
  const std::string bin = DOASIDO_BIN;
  const std::string pool = Pool(clips, size).string();
  const std::string single = (dir / "single/d.db").string();
  const std::string parent = (dir / "parent/d.db").string();
  for (const auto& db : {single, parent}) {
    std::filesystem::create_directories(std::filesystem::path(db).parent_path());
    Run(bin + " init --pipeline filters --db " + db);
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
  return one;
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
  if (pipeline_clips > 0) {
    const double one_run_s = Overhead(dir, pipeline_clips, size);
    ThroughSlurm(dir, Pool(pipeline_clips, size).string(), one_run_s, dir / "single/d.db");
  }
  std::filesystem::remove_all(dir);
  return 0;
}
