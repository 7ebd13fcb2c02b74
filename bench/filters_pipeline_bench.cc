// The default filter pipeline as a user runs it, `doasido run --jobs 1` over
// probe, filters_analyze and the five verdict stages, against FFmpeg's own
// scene-change filter on the same files, side by side in one run:
//   ffmpeg -hide_banner -nostdin -i FILE -vf "select='gt(scene,0.3)'" -f null -
// Both sides are counted in frames per CPU second (user + system of the
// process and every child it waited for: the learned hand detector's Node
// process included). Each side runs `repeats` times, alternating; the
// fastest run counts. Three configurations of filters_analyze: no detector
// (use_builtin_detector = false: the price of the filters themselves), the
// default learned hand detector (MediaPipe Hands, 5 samples/s), and no
// detector with decode = "fast" (no deblocking, YUV scaled straight to
// analysis size: not PySceneDetect's pixels).
// Each stage's share is its summed run time (stage_runs.duration_s, one
// worker, so wall ~ CPU) over the run's CPU; the rest is start-up, queue
// bookkeeping and ingest-free claiming.
//
// Usage: filters_pipeline_bench [repeats=3]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "bench/child_cpu.h"
#include "tests/db_dump.h"

namespace {

namespace fs = std::filesystem;

using doasido::bench::ChildCpu;

void Must(const std::vector<std::string>& argv) {
  if (ChildCpu(argv) < 0) {
    std::string line;
    for (const auto& a : argv) line += a + " ";
    std::fprintf(stderr, "failed: %s\n", line.c_str());
    std::exit(1);
  }
}

using doasido::testing::QueryRows;

const std::vector<std::string> kStages = {"probe",       "filters_analyze", "shot_boundary",
                                          "interaction", "out_of_frame",    "activity",
                                          "camera_motion"};

struct PipelineRun {
  double cpu = 1e30;                    // best run
  std::map<std::string, double> stage;  // seconds per stage in that run
  double frames = 0;                    // frames analysed
  std::vector<std::string> verdicts;    // per clip: first reject or pass
};

// One fresh database, the clips ingested (not timed), then `doasido run`.
PipelineRun RunOnce(const fs::path& dir, const fs::path& list, const std::string& config_text) {
  const std::string bin = DOASIDO_BIN;
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string db = (dir / "d.db").string(), config = (dir / "filters.toml").string();
  std::ofstream(config) << config_text;
  std::vector<std::string> init = {bin, "init", "--db", db, "--config", config, "--pipeline"};
  init.insert(init.end(), kStages.begin(), kStages.end());
  Must(init);
  Must({bin, "ingest", "--db", db, list.string()});
  PipelineRun run;
  run.cpu = ChildCpu({bin, "run", "--db", db, "--config", config, "--jobs", "1"});
  if (run.cpu < 0) {
    std::fprintf(stderr, "doasido run failed on %s\n", db.c_str());
    std::exit(1);
  }
  for (const auto& row : QueryRows(db, "SELECT stage, SUM(duration_s) FROM stage_runs GROUP BY 1")) {
    const auto bar = row.find('|');
    run.stage[row.substr(0, bar)] = std::atof(row.substr(bar + 1).c_str());
  }
  for (const auto& f : QueryRows(db, "SELECT json_extract(data, '$.clip.frames') FROM measurements"
                                 " WHERE stage = 'filters_analyze'")) {
    run.frames += std::atof(f.c_str());
  }
  run.verdicts = QueryRows(db,
                       "SELECT c.id || ' ' || COALESCE((SELECT stage || ':' || reason FROM"
                       " verdicts v WHERE v.clip_id = c.id AND v.verdict = 'reject' ORDER BY"
                       " v.rowid LIMIT 1), 'pass') FROM clips c ORDER BY c.id");
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  const fs::path data(DOASIDO_SHARED_DATA);
  const std::vector<fs::path> files = {
      data / "videos" / "02_cups.mp4", data / "videos" / "03_blocks.mp4",
      data / "videos" / "apple.mp4", data / "videos" / "bedroom.mp4",
      data / "shots" / "testvideo.mp4"};
  const fs::path dir = fs::temp_directory_path() / "doasido-filters-pipeline-bench";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path list = dir / "clips.csv";
  {
    std::ofstream out(list);
    out << "video\n";
    for (const auto& f : files) out << fs::absolute(f).string() << "\n";
  }
  const std::vector<std::pair<std::string, std::string>> configs = {
      {"no detector", "[filters_analyze]\nuse_builtin_detector = false\n"},
      {"learned detector (default)", "[filters_analyze]\nhand_detector = \"learned\"\n"},
      {"no detector, decode = fast",
       "[filters_analyze]\nuse_builtin_detector = false\ndecode = \"fast\"\n"}};

  std::vector<PipelineRun> best(configs.size());
  double ffmpeg = 0;
  std::vector<double> ffmpeg_file(files.size(), 1e30);
  for (int r = 0; r < repeats; ++r) {
    for (size_t c = 0; c < configs.size(); ++c) {
      PipelineRun run = RunOnce(dir / ("run" + std::to_string(c)), list, configs[c].second);
      if (run.cpu < best[c].cpu) best[c] = run;
    }
    for (size_t f = 0; f < files.size(); ++f) {
      const double cpu = doasido::bench::FfmpegSceneCpu(files[f].string());
      if (cpu > 0) ffmpeg_file[f] = std::min(ffmpeg_file[f], cpu);
    }
  }
  for (double f : ffmpeg_file) ffmpeg += f;

  const double frames = best[0].frames;
  std::printf("\nThe filter pipeline through `doasido run --jobs 1` vs ffmpeg select='gt(scene,0.3)'"
              " on %zu files, %.0f frames (frames per CPU second, best of %d)\n",
              files.size(), frames, repeats);
  std::printf("%-28s %9s %9s %8s\n", "", "CPU s", "frames/s", "ratio");
  std::printf("%-28s %9.2f %9.0f %8s\n", "ffmpeg scene filter", ffmpeg, frames / ffmpeg, "1.00x");
  for (size_t c = 0; c < configs.size(); ++c) {
    std::printf("%-28s %9.2f %9.0f %7.2fx%s\n", configs[c].first.c_str(), best[c].cpu,
                frames / best[c].cpu, ffmpeg / best[c].cpu, c == 0 ? "  (goal >= 1.0x)" : "");
  }
  std::printf("\nEach stage's share of the run's CPU (summed stage run times)\n%-16s", "stage");
  for (const auto& c : configs) std::printf(" %28s", c.first.c_str());
  std::printf("\n");
  for (const auto& stage : kStages) {
    std::printf("%-16s", stage.c_str());
    for (const auto& run : best) {
      const double s = run.stage.count(stage) ? run.stage.at(stage) : 0;
      std::printf(" %19.2f s %6.1f%%", s, 100 * s / run.cpu);
    }
    std::printf("%s\n", stage == "probe" ? "  (goal < 3%)" : "");
  }
  std::printf("%-16s", "the rest");
  for (const auto& run : best) {
    double staged = 0;
    for (const auto& [stage, s] : run.stage) staged += s;
    std::printf(" %19.2f s %6.1f%%", run.cpu - staged, 100 * (run.cpu - staged) / run.cpu);
  }
  const double detector = best[1].cpu - best[0].cpu;
  std::printf("\n\nlearned detector: %.2f CPU s more = %.1f ms per video frame\n", detector,
              1000 * detector / frames);
  std::printf("\nverdicts (first reject, else pass), by clip:\n");
  for (size_t i = 0; i < best[0].verdicts.size(); ++i) {
    std::printf("  %-16s no detector: %-28s learned: %s\n",
                files[i].filename().c_str(), best[0].verdicts[i].c_str(),
                i < best[1].verdicts.size() ? best[1].verdicts[i].c_str() : "");
  }
  fs::remove_all(dir);
  return 0;
}
