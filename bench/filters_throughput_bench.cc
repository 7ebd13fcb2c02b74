// Frames per second per core of the filters' single analysis pass (decode +
// all five signal extractors + the built-in hand/object detector), side by
// side in the same run with FFmpeg's own scene-change filter on the same
// files:
//   ffmpeg -hide_banner -i FILE -vf "select='gt(scene,0.3)'" -f null -
// "Per core" divides frames by CPU seconds (user + system, all threads), so
// the multi-threaded decoders of both sides are compared fairly. Each side
// runs `repeats` times; the fastest run counts. Both decode paths of the
// analysis stage are measured (filters_analyze.decode = "exact", the
// default, PySceneDetect's pixels; and "fast"), each also as decode only (the
// floor), and the built-in interaction detector's verdicts on the four real
// videos are printed.
//
// A second table splits the analysis by signal: every file decoded once
// (exact) into memory, then each signal extractor alone over those frames,
// in milliseconds of CPU per frame, next to the decode's own cost.
//
// Usage: filters_throughput_bench [repeats=3] [config.toml]
// (config: a [filters_analyze] table, as `doasido --config` takes, to
// measure other settings than the defaults)
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "bench/child_cpu.h"
#include "filters/analyze.h"
#include "filters/frame_analyzer.h"
#include "stages/verdict_stages.h"

namespace doasido::filters {
namespace {

using namespace doasido::stages;  // the filters' queue stages

using bench::Seconds;

// This process and its waited-for children: the learned hand detector's
// Node process is waited for when an analysis ends, so its CPU counts.
double SelfCpu() {
  rusage u{}, c{};
  getrusage(RUSAGE_SELF, &u);
  getrusage(RUSAGE_CHILDREN, &c);
  return Seconds(u.ru_utime) + Seconds(u.ru_stime) + Seconds(c.ru_utime) + Seconds(c.ru_stime);
}

struct Row {
  std::string name;
  std::int64_t frames = 0;
  // CPU seconds, best run; [0] exact decode, [1] fast decode.
  double decode[2] = {1e30, 1e30}, given[2] = {1e30, 1e30}, ours[2] = {1e30, 1e30};
  double ffmpeg = 1e30;
};

// CPU seconds of `work()`.
template <typename F>
double Cpu(F&& work) {
  const double t0 = SelfCpu();
  work();
  return SelfCpu() - t0;
}

// CPU milliseconds per frame of each signal extractor alone, on frames
// decoded beforehand (so the decode is not in any figure but its own).
void SignalCosts(const std::vector<std::filesystem::path>& files, int repeats,
                 const AnalyzeConfig& config) {
  std::printf("\nPer signal, CPU ms per frame (frames decoded once beforehand, exact decode; best"
              " of %d)\n%-15s %7s %7s %7s %9s %7s %8s %7s %7s\n", repeats, "file", "decode",
              "gray", "shot", "activity", "camera", "interact", "out_frm", "sum");
  for (const auto& file : files) {
    std::vector<AnalysisFrame> frames;
    VideoGeometry geometry;
    DecoderOptions options;
    options.exact_scaling = true;
    options.skip_loop_filter = false;
    double decode = 1e30;
    for (int r = 0; r < repeats; ++r) {
      frames.clear();
      decode = std::min(decode, Cpu([&] {
        VideoDecoder decoder(file, options);
        geometry = decoder.geometry();
        AnalysisFrame frame;
        while (decoder.Next(&frame)) {
          frames.push_back(frame);
          frames.back().bgr = frame.bgr.clone();
        }
      }));
    }
    std::vector<FrameContext> contexts(frames.size());
    double gray = 1e30;
    for (int r = 0; r < repeats; ++r) {
      gray = std::min(gray, Cpu([&] {
        for (size_t i = 0; i < frames.size(); ++i) {
          contexts[i].frame = &frames[i];
          contexts[i].ordinal = static_cast<std::int64_t>(i);
          cv::cvtColor(frames[i].bgr, contexts[i].gray, cv::COLOR_BGR2GRAY);
        }
      }));
    }
    auto cost = [&](auto make) {
      double best = 1e30;
      for (int r = 0; r < repeats; ++r) {
        auto consumer = make();
        best = std::min(best, Cpu([&] {
          consumer->Begin(geometry);
          for (FrameContext& context : contexts) {
            FrameContext copy = context;
            consumer->Consume(copy);
          }
          consumer->Finish();
        }));
      }
      return best;
    };
    const double shot = cost([&] { return std::make_unique<ShotSignalExtractor>(config.shot); });
    const double activity =
        cost([&] { return std::make_unique<ActivityExtractor>(config.activity); });
    const double camera =
        cost([&] { return std::make_unique<CameraMotionExtractor>(config.camera_motion); });
    const double interaction = cost([&] { return std::make_unique<InteractionExtractor>(); });
    const double out =
        cost([&] { return std::make_unique<OutOfFrameExtractor>(config.out_of_frame); });
    const double n = static_cast<double>(frames.size()) / 1000;
    std::printf("%-15s %7.3f %7.3f %7.3f %9.3f %7.3f %8.3f %7.3f %7.3f\n",
                file.filename().c_str(), decode / n, gray / n, shot / n, activity / n,
                camera / n, interaction / n, out / n,
                (gray + shot + activity + camera + interaction + out) / n);
  }
  std::printf("(decode: libavcodec + full-size BGR + cv::resize to analysis size; sum: every"
              " signal with the shared gray image, no detector)\n");
  std::fflush(stdout);
}

}  // namespace
}  // namespace doasido::filters

int main(int argc, char** argv) {
  using namespace doasido;
  using namespace doasido::filters;
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  const std::filesystem::path data(DOASIDO_SHARED_DATA);
  const std::vector<std::filesystem::path> files = {
      data / "videos" / "02_cups.mp4", data / "videos" / "03_blocks.mp4",
      data / "videos" / "apple.mp4", data / "videos" / "bedroom.mp4",
      data / "shots" / "testvideo.mp4"};

  AnalyzeConfig config;
  if (argc > 2) ReadSection(LoadConfigFile(argv[2]), "filters_analyze", config);
  SignalCosts(files, repeats, config);

  std::vector<Row> rows;
  std::vector<std::pair<std::string, Json>> analyses;
  for (const auto& file : files) {
    Row row;
    row.name = file.filename().string();
    for (int r = 0; r < repeats; ++r) {
      for (int mode = 0; mode < 2; ++mode) {
        AnalyzeConfig all = config;
        all.decode = mode == 0 ? "exact" : "fast";
        DecoderOptions options;
        options.exact_scaling = mode == 0;
        options.skip_loop_filter = mode == 1;
        row.decode[mode] = std::min(row.decode[mode], Cpu([&] {
          VideoDecoder decoder(file, options);
          AnalysisFrame frame;
          std::int64_t n = 0;
          while (decoder.Next(&frame)) ++n;
          row.frames = n;
          benchmark::DoNotOptimize(frame.bgr.data);
        }));
        row.ours[mode] = std::min(row.ours[mode], Cpu([&] {
          ClipAnalysis analysis = AnalyzeClip(file, {}, {}, all);
          if (r == 0 && mode == 0) analyses.emplace_back(row.name, analysis.measurements);
        }));
        AnalyzeConfig no_detector = all;
        no_detector.use_builtin_detector = false;
        row.given[mode] = std::min(row.given[mode], Cpu([&] {
          benchmark::DoNotOptimize(AnalyzeClip(file, {}, {}, no_detector).measurements.size());
        }));
      }
      const double f = bench::FfmpegSceneCpu(file.string());
      if (f > 0) row.ffmpeg = std::min(row.ffmpeg, f);
    }
    rows.push_back(row);
  }

  std::printf(
      "\nSingle analysis pass vs ffmpeg select='gt(scene,0.3)' (frames / CPU second, "
      "best of %d)\n",
      repeats);
  std::printf("%-15s %6s | %26s | %26s | %7s | %6s %6s\n", "", "", "decode = exact (default)",
              "decode = fast", "ffmpeg", "ratio", "ratio");
  std::printf("%-15s %6s | %8s %8s %8s | %8s %8s %8s | %7s | %6s %6s\n", "file", "frames",
              "decode", "given", "all", "decode", "given", "all", "scene", "exact", "fast");
  double all_frames = 0, all_ours[2] = {0, 0}, all_ffmpeg = 0;
  for (const Row& r : rows) {
    const double n = static_cast<double>(r.frames);
    std::printf("%-15s %6lld | %8.0f %8.0f %8.0f | %8.0f %8.0f %8.0f | %7.0f | %5.2fx %5.2fx\n",
                r.name.c_str(), static_cast<long long>(r.frames), n / r.decode[0],
                n / r.given[0], n / r.ours[0], n / r.decode[1], n / r.given[1], n / r.ours[1],
                n / r.ffmpeg, r.ffmpeg / r.ours[0], r.ffmpeg / r.ours[1]);
    all_frames += n;
    all_ours[0] += r.ours[0];
    all_ours[1] += r.ours[1];
    all_ffmpeg += r.ffmpeg;
  }
  std::printf("%-15s %6.0f | %8s %8s %8.0f | %8s %8s %8.0f | %7.0f | %5.2fx %5.2fx  (goal >= 3x)\n",
              "all", all_frames, "", "", all_frames / all_ours[0], "", "",
              all_frames / all_ours[1], all_frames / all_ffmpeg, all_ffmpeg / all_ours[0],
              all_ffmpeg / all_ours[1]);
  std::printf(
      "frames per CPU second. decode: the decoder alone at analysis size; given: every signal "
      "with boxes given (no detector); all: every signal + the default (learned) hand detector, "
      "its Node process's CPU included; "
      "ratio = all / ffmpeg scene\n");

  std::printf("\nDefault (learned) hand detector (no annotations given) on the real videos\n");
  std::printf("%-16s %6s %12s %8s %9s %22s %22s\n", "file", "hands", "interaction", "missing",
              "hand_cut", "interaction", "out_of_frame");
  std::printf("%-16s %6s %12s %8s %9s %22s %22s\n", "", "frac", "frac", "frac", "frac", "verdict",
              "verdict");
  InteractionStage interaction;
  OutOfFrameStage out;
  for (const auto& [name, m] : analyses) {
    if (name == "testvideo.mp4") continue;
    const Json clip = m.at("clip");
    const StageResult i = *interaction.Redecide({{"clip", clip}, {"signals", m.at("interaction")}});
    const StageResult o = *out.Redecide({{"clip", clip}, {"signals", m.at("out_of_frame")}});
    const Json& is = i.measurements.at("summary");
    const Json& os = o.measurements.at("summary");
    auto verdict = [](const StageResult& r) {
      std::string v = r.verdict == Verdict::kPass     ? "pass"
                      : r.verdict == Verdict::kReject ? "reject"
                                                      : "flag";
      return r.reason.empty() ? v : v + ":" + r.reason;
    };
    std::printf("%-16s %6.2f %12.2f %8.2f %9.2f %22s %22s\n", name.c_str(),
                is.at("hand_fraction").get<double>(), is.at("interaction_fraction").get<double>(),
                os.at("missing_fraction").get<double>(), os.at("hand_cut_fraction").get<double>(),
                verdict(i).c_str(), verdict(o).c_str());
  }
  std::printf(
      "(ground truth, data/README.md: cups and blocks are hand-object clips, blocks' hand "
      "enters from the top edge; bedroom has people but no hand-object interaction; apple "
      "has no hands)\n");
  return 0;
}
