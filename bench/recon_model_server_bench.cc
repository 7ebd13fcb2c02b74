// The bundle stage per clip: a model command started for every clip against
// a model server started once per worker (recon/bundle/model_server.h), both the
// same stand-in (tools/bundle_server.py) with a simulated model load.
//
//   recon_model_server_bench [clips] [load_s] [jobs]
//
// `clips` synthetic clips (default 20; 96 x 72 px, 24 frames, rendered once
// into the temporary folder) through a pipeline of the bundle stage alone,
// `doasido run --jobs <jobs>` (default 1), once per mode. Prints per mode the
// wall time of the run, per clip, and the stage's own mean seconds per clip
// (its "seconds" measurement), then the ratio command / server. The load
// dominates the command mode: expect clips x load_s / jobs for it.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "testing/db_dump.h"

namespace {

using Clock = std::chrono::steady_clock;

void Run(const std::string& command) {
  if (std::system((command + " > /dev/null 2>&1").c_str()) != 0) {
    std::fprintf(stderr, "failed: %s\n", command.c_str());
    std::exit(1);
  }
}

struct ModeResult {
  double wall_s = 0, stage_mean_s = 0;
  long done = 0;
};

ModeResult RunMode(const std::filesystem::path& dir, const std::string& name,
                   const std::string& bundle_toml, const std::filesystem::path& list, int jobs) {
  const std::string bin = DOASIDO_BIN;
  const auto db = dir / name / "d.db";
  std::filesystem::remove_all(db.parent_path());
  std::filesystem::create_directories(db.parent_path());
  std::ofstream(dir / name / "config.toml") << "[bundle]\n" << bundle_toml;
  Run(bin + " init --db " + db.string() + " --pipeline bundle");
  Run(bin + " ingest --db " + db.string() + " " + list.string());
  const auto start = Clock::now();
  Run(bin + " run --db " + db.string() + " --jobs " + std::to_string(jobs) + " --config " +
      (dir / name / "config.toml").string());
  ModeResult r;
  r.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  const auto rows = doasido::testing::QueryRows(
      db, "SELECT COUNT(*), AVG(json_extract(m.data, '$.seconds')) FROM stage_runs s JOIN"
          " measurements m ON m.clip_id = s.clip_id AND m.stage = s.stage WHERE s.state = 'done'");
  const auto bar = rows.at(0).find('|');
  r.done = std::stol(rows[0].substr(0, bar));
  r.stage_mean_s = r.done ? std::stod(rows[0].substr(bar + 1)) : 0;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const int clips = argc > 1 ? std::atoi(argv[1]) : 20;
  const double load_s = argc > 2 ? std::atof(argv[2]) : 20.0;
  const int jobs = argc > 3 ? std::atoi(argv[3]) : 1;
  const auto dir = std::filesystem::temp_directory_path() / "doasido-model-server-bench";
  const auto pool = dir / ("pool-" + std::to_string(clips));
  if (!std::filesystem::exists(pool / "clips.csv")) {
    Run(std::string(DOASIDO_BIN) + " synth --out " + pool.string() + " --clips " +
        std::to_string(clips) + " --frames 24 --width 96 --height 72 --mix clean=1 --seed 3" +
        " --no-annotations");
  }
  const std::string tool = "/usr/bin/python3 " + std::string(DOASIDO_SOURCE_DIR) + "/tools/bundle_server.py";
  const std::string load = " --load-s " + std::to_string(load_s);
  std::printf("%d clips, simulated load %.1f s, doasido run --jobs %d\n", clips, load_s, jobs);
  const ModeResult server = RunMode(dir, "server", "server = \"" + tool + load + "\"\n",
                                    pool / "clips.csv", jobs);
  std::printf("%-8s %6s %10s %14s %16s\n", "mode", "done", "wall s", "wall s/clip",
              "stage s/clip");
  auto print = [&](const char* mode, const ModeResult& r) {
    std::printf("%-8s %6ld %10.1f %14.2f %16.2f\n", mode, r.done, r.wall_s, r.wall_s / clips,
                r.stage_mean_s);
    std::fflush(stdout);
  };
  print("server", server);
  const ModeResult command = RunMode(
      dir, "command",
      "command = \"" + tool + load + " --clip {clip} --video {video} --output {output}\"\n",
      pool / "clips.csv", jobs);
  print("command", command);
  std::printf("command / server: %.1fx wall time\n", command.wall_s / server.wall_s);
  return command.done == clips && server.done == clips ? 0 : 1;
}
