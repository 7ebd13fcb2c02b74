// Kinematic retargeting of the real 621-frame human hand sequence
// (../shared/data/retarget/human_hand_keypoints_right.csv, dex-retargeting
// sample) onto the three hands. Prints, per hand: the adapted scale; mean
// and 95th-percentile fingertip error with one start per frame (warm start)
// and with the default multi-start; on the worst 10% of frames of the
// single-start run, the error of single vs multi-start from the same warm
// start; and the cost of one retargeted frame against raw mj_step of the
// hand scene (hand + floor + YCB sugar box), measured in the same run.
// Google Benchmark timings of the same two operations follow the table.
// Then, per hand, the track as the stages solve it (Solve: random starts at
// the first frame and after a jump only) against the multi-start run with
// the old Ceres tolerance (1e-12): error and ms per hand-frame, wall and CPU.
// Flags: --hands=NAME (one hand), --track_only (the track solve alone),
// --tolerance=T (its Ceres tolerance), --benchmark_filter=NONE (no timings).
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <filesystem>
#include <numeric>

#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include "core/file_text.h"
#include "core/mesh.h"
#include "retarget/kinematic/kinematic_retarget.h"
#include "retarget/scene/scene_builder.h"
#include "robot/embodiment.h"

namespace {

using namespace doasido;
using namespace doasido::retarget;
using Clock = std::chrono::steady_clock;

const std::filesystem::path kData = DOASIDO_SHARED_DATA;
const char* kHands[] = {"sharpa_right", "shadow", "allegro"};

double Mean(const std::vector<double>& v) {
  return v.empty() ? 0 : std::accumulate(v.begin(), v.end(), 0.0) / v.size();
}
double P95(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[static_cast<size_t>(0.95 * (v.size() - 1))];
}

std::filesystem::path SceneDir() {
  static const std::filesystem::path dir = [] {
    const auto d = std::filesystem::temp_directory_path() / "doasido-retarget-bench-scene";
    SceneConfig config;
    Pose pose;
    pose.t = Vec3(0.15, 0.0, 0.0);  // beside the hand
    BuildObjectScene(LoadMesh(kData / "meshes/ycb/004_sugar_box_textured.obj"), pose, config, d);
    return d;
  }();
  return dir;
}

struct Row {
  std::string hand;
  double scale = 0;
  double single_mean = 0, single_p95 = 0, multi_mean = 0, multi_p95 = 0;
  double worst_single = 0, worst_multi = 0;
  int worst_frames = 0;
  double ms_per_frame = 0;   // multi-start on every frame (before jump_distance)
  double track_mean = 0, track_p95 = 0, track_ms = 0, track_cpu_ms = 0;  // Solve: restarts at jumps only
  int track_jumps = 0;
  double steps_per_s = 0;    // mj_step of the hand scene
};

// --track_only: only the track solve (Solve); --tolerance=T: its Ceres tolerance.
bool g_track_only = false;
double g_tolerance = 0;

Row Measure(const char* name, const std::vector<Keypoints21>& frames) {
  Row row;
  row.hand = name;
  const Embodiment e = FindEmbodiment(name, kData / "robots");
  const HandModel hand = BuildHandModel(e);

  KinematicConfig single;
  single.restarts = 0;
  KinematicRetargeter a(hand, single);
  row.scale = a.AdaptScale(frames);
  std::vector<double> err_a;
  std::vector<Eigen::VectorXd> q_a;
  for (size_t t = 0; t < (g_track_only ? 0 : frames.size()); ++t) {
    const FrameSolution s = a.SolveFrame(frames[t], t ? &q_a.back() : nullptr);
    q_a.push_back(s.qpos);
    err_a.push_back(s.fingertip_mean);
  }
  row.single_mean = Mean(err_a);
  row.single_p95 = P95(err_a);

  KinematicConfig multi;  // default restarts, on every frame below, with the tolerance before 2026-11-28
  multi.scale = row.scale;
  multi.tolerance = 1e-12;
  KinematicRetargeter b(hand, multi);
  std::vector<double> err_b;
  Eigen::VectorXd prev;
  const auto t0 = Clock::now();
  for (size_t t = 0; t < (g_track_only ? 0 : frames.size()); ++t) {
    const FrameSolution s = b.SolveFrame(frames[t], t ? &prev : nullptr);
    prev = s.qpos;
    err_b.push_back(s.fingertip_mean);
  }
  row.ms_per_frame = std::chrono::duration<double, std::milli>(Clock::now() - t0).count() / frames.size();
  row.multi_mean = Mean(err_b);
  row.multi_p95 = P95(err_b);

  // The sequence as the stages solve it (Solve): random starts only at the
  // first frame and after a jump.
  {
    KinematicConfig defaults;
    defaults.scale = row.scale;
    if (g_tolerance > 0) defaults.tolerance = g_tolerance;
    KinematicRetargeter track(hand, defaults);
    const auto w0 = Clock::now();
    const std::clock_t c0 = std::clock();
    const HandTrajectory t = track.Solve(frames, {}, 30.0);
    row.track_cpu_ms = 1000.0 * (std::clock() - c0) / CLOCKS_PER_SEC / frames.size();
    row.track_ms = std::chrono::duration<double, std::milli>(Clock::now() - w0).count() / frames.size();
    row.track_mean = Mean(t.fingertip_error);
    row.track_p95 = P95(t.fingertip_error);
    for (size_t f = 1; f < frames.size(); ++f) {
      row.track_jumps += (frames[f] - frames[f - 1]).rowwise().norm().maxCoeff() > multi.jump_distance;
    }
  }

  if (g_track_only) return row;
  // Worst 10% of the single-start run, re-solved from the same warm start.
  std::vector<size_t> order(frames.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t i, size_t j) { return err_a[i] > err_a[j]; });
  order.resize(std::max<size_t>(1, frames.size() / 10));
  row.worst_frames = static_cast<int>(order.size());
  KinematicConfig many = multi;
  many.restarts = 8;
  KinematicRetargeter c(hand, many);
  std::vector<double> ws, wm;
  for (size_t t : order) {
    ws.push_back(err_a[t]);
    wm.push_back(c.SolveFrame(frames[t], t ? &q_a[t - 1] : nullptr).fingertip_mean);
  }
  row.worst_single = Mean(ws);
  row.worst_multi = Mean(wm);

  // Raw simulation throughput of the hand scene.
  const HandModel scene = BuildHandModel(e, TryReadFile(SceneDir() / "scene.xml").value_or(""), SceneDir());
  DataPtr d = MakeData(scene.model.get());
  const int steps = 4000;
  const auto s0 = Clock::now();
  for (int i = 0; i < steps; ++i) mj_step(scene.model.get(), d.get());
  row.steps_per_s = steps / std::chrono::duration<double>(Clock::now() - s0).count();
  return row;
}

void BM_MjStep(benchmark::State& state) {
  const Embodiment e = FindEmbodiment(kHands[state.range(0)], kData / "robots");
  const HandModel scene = BuildHandModel(e, TryReadFile(SceneDir() / "scene.xml").value_or(""), SceneDir());
  DataPtr d = MakeData(scene.model.get());
  for (auto _ : state) mj_step(scene.model.get(), d.get());
  state.SetLabel(kHands[state.range(0)]);
}
BENCHMARK(BM_MjStep)->DenseRange(0, 2);

void BM_RetargetFrame(benchmark::State& state) {
  static const auto frames = ReadKeypointCsv(kData / "retarget/human_hand_keypoints_right.csv");
  const HandModel hand = BuildHandModel(FindEmbodiment(kHands[state.range(0)], kData / "robots"));
  KinematicRetargeter r(hand);
  r.AdaptScale(frames);
  Eigen::VectorXd prev = r.SolveFrame(frames[0], nullptr).qpos;
  size_t t = 1;
  for (auto _ : state) {
    prev = r.SolveFrame(frames[t], &prev).qpos;
    t = t + 1 < frames.size() ? t + 1 : 1;
  }
  state.SetLabel(kHands[state.range(0)]);
}
BENCHMARK(BM_RetargetFrame)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_level(spdlog::level::warn);
  const auto frames = ReadKeypointCsv(kData / "retarget/human_hand_keypoints_right.csv");
  std::printf("Kinematic retargeting of %zu real frames (dex-retargeting sample), fingertip error in mm\n"
              "after scale adaptation; single = warm start only, multi = warm start + 4 random starts.\n\n",
              frames.size());
  std::printf("%-13s %6s | %8s %8s | %8s %8s | %5s %9s %9s | %9s %10s %12s\n", "hand", "scale",
              "1x mean", "1x p95", "mx mean", "mx p95", "worst", "1x worst", "9x worst",
              "ms/frame", "mj_step/s", "frame/steps");
  std::vector<Row> rows;
  std::string only;  // --hands=NAME measures that hand alone
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]).rfind("--hands=", 0) == 0) only = argv[i] + 8;
    if (std::string(argv[i]) == "--track_only") g_track_only = true;
    if (std::string(argv[i]).rfind("--tolerance=", 0) == 0) g_tolerance = std::stod(argv[i] + 12);
  }
  for (const char* name : kHands) {
    if (!only.empty() && only != name) continue;
    const Row& r = rows.emplace_back(Measure(name, frames));
    std::printf("%-13s %6.3f | %8.2f %8.2f | %8.2f %8.2f | %5d %9.2f %9.2f | %9.3f %10.0f %12.1f\n",
                r.hand.c_str(), r.scale, 1000 * r.single_mean, 1000 * r.single_p95,
                1000 * r.multi_mean, 1000 * r.multi_p95, r.worst_frames, 1000 * r.worst_single,
                1000 * r.worst_multi, r.ms_per_frame, r.steps_per_s,
                r.ms_per_frame / 1000.0 * r.steps_per_s);
  }
  std::printf("\nAs the stages solve a track (Solve: warm start, random starts only at the first frame and\n"
              "after a jump of more than %.0f mm), against mx above (random starts on every frame):\n",
              1000 * KinematicConfig{}.jump_distance);
  std::printf("%-13s | %8s %8s %9s | %8s %8s %9s %9s %6s\n", "hand", "mx mean", "mx p95", "mx ms/f",
              "tr mean", "tr p95", "tr ms/f", "tr cpu ms", "jumps");
  for (const Row& r : rows) {
    std::printf("%-13s | %8.2f %8.2f %9.2f | %8.2f %8.2f %9.2f %9.2f %6d\n", r.hand.c_str(),
                1000 * r.multi_mean, 1000 * r.multi_p95, r.ms_per_frame, 1000 * r.track_mean,
                1000 * r.track_p95, r.track_ms, r.track_cpu_ms, r.track_jumps);
  }
  std::printf("\nworst = the 10%% of frames with the largest single-start error, re-solved from the same\n"
              "warm start with 8 random starts (9x). frame/steps = one multi-start retargeted frame\n"
              "costs this many mj_step calls of the same hand's scene (hand + floor + sugar box).\n\n");
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
