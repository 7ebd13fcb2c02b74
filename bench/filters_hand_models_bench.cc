// CPU time of MediaPipe Hands' two models per sample, the native runtime
// (our TFLite reader + XNNPACK, in process) against the reference (TFLite's
// WebAssembly runtime in Node), in the same run, on the same samples: every
// real sample video (../shared/data/videos) at analysis size, 5 samples per
// second, tracked from one sample to the next as the analysis pass does.
//
// Per sample: the models' CPU milliseconds (palm detector + landmark model
// per hand; the calling thread's for native, the Node process's for wasm)
// and, for native, the whole Detect() (with the crops' resampling and the
// post-processing) on this thread. Three ways of sampling:
//   every palm:  the palm detector on every sample with fewer than two
//                hands tracked (MediaPipe's VIDEO mode; palm_every = 1);
//   tracked:     the palm detector on every palm_every-th sample while a
//                hand is tracked;
//   gated:       tracked, and on a sample with no hand tracked the palm
//                detector runs only where the palm gate lets it (PalmGate:
//                every no_hand_palm_every-th such sample, where the frame
//                changed since the last one it ran on; the analysis pass's
//                default), both runtimes;
//   analysis:    as the analysis pass runs them (LearnedHandDetector with
//                its defaults: tracked, and still samples keep the last
//                hands without a model run): model ms per sample of the
//                pass, and the share of samples the models saw.
//
// The model pair (full or lite) is the second argument; each model alone
// is timed for both pairs.
//
// Usage: filters_hand_models_bench [samples per video=40] [full|lite|lite_landmark=full]
//          [no_hand_palm_every] [no_hand_changed_fraction] (the palm gate,
//          LearnedDetectorConfig's defaults when not given)
//          [unchanged_crop_fraction=0] (HandLandmarkerOptions: a tracked hand
//          whose crop barely changed keeps its last keypoints; applied to
//          the "gated" column and the WebAssembly one)
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "filters/hand_landmarker.h"
#include "filters/hand_models.h"
#include "filters/learned_hand_detector.h"
#include "video/video_decoder.h"

namespace doasido::filters {
namespace {

double ThreadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

struct Sampled {
  VideoGeometry geometry;
  int every = 1;
  std::vector<cv::Mat> frames, grays;
};

Sampled Samples(const std::filesystem::path& video, int count) {
  VideoDecoder decoder(video, DecoderOptions{});
  Sampled out;
  out.geometry = decoder.geometry();
  const LearnedDetectorConfig defaults;
  out.every = static_cast<int>(SampleEvery(out.geometry, defaults));
  const int every = out.every;
  AnalysisFrame frame;
  for (int i = 0; static_cast<int>(out.frames.size()) < count && decoder.Next(&frame); ++i) {
    if (i % every != 0) continue;
    out.frames.push_back(frame.bgr.clone());
    out.grays.emplace_back();
    cv::cvtColor(frame.bgr, out.grays.back(), cv::COLOR_BGR2GRAY);
  }
  return out;
}

// The analysis pass's detector on the samples (it sees only the sample
// frames, which is all it looks at): model CPU ms per sample, and how many
// samples ran the models.
void Analysis(const Sampled& s, LearnedDetectorConfig config, double* ms_per_sample,
              int* model_samples) {
  LearnedHandDetector detector(config, "");
  detector.Begin(s.geometry);
  AnalysisFrame frame;
  for (std::size_t i = 0; i < s.frames.size(); ++i) {
    FrameContext context;
    frame.index = static_cast<std::int64_t>(i) * s.every;
    frame.bgr = s.frames[i];
    context.frame = &frame;
    context.ordinal = frame.index;
    context.gray = s.grays[i];
    detector.Consume(context);
  }
  const Json m = detector.Measurements();
  double total = 0;
  for (const Json& sample : m.at("samples")) total += sample.at("ms").get<double>();
  *ms_per_sample = s.frames.empty() ? 0 : total / s.frames.size();
  *model_samples = m.at("model_samples").get<int>();
}

struct Totals {
  int samples = 0, hands = 0;
  double model_ms = 0, detect_ms = 0;
};

// The landmarker on every sample; with a palm gate, a sample with no hand
// tracked that the gate keeps from the palm detector costs nothing but the
// gate (as in LearnedHandDetector).
void Measure(HandLandmarker& landmarker, const Sampled& s, PalmGate* gate, Totals* t) {
  landmarker.Reset();
  if (gate) gate->Reset();
  for (std::size_t i = 0; i < s.frames.size(); ++i) {
    ++t->samples;
    const double start = ThreadCpuMs();
    if (gate && !landmarker.tracking() && !gate->Look(s.grays[i])) {
      t->detect_ms += ThreadCpuMs() - start;
      continue;
    }
    t->hands += static_cast<int>(landmarker.Detect(s.frames[i]).size());
    t->detect_ms += ThreadCpuMs() - start;
    t->model_ms += landmarker.last_ms();
  }
}

// Each model alone, `runs` times on the same input: CPU ms per run.
void PerModel(HandModels& models, int runs, double* palm_ms, double* landmark_ms) {
  std::vector<float> palm_in(kPalmInputSize * kPalmInputSize * 3, 0.5f);
  std::vector<float> landmark_in(kLandmarkInputSize * kLandmarkInputSize * 3, 0.5f);
  PalmOutput p;
  LandmarkOutput l;
  models.TakeModelMs();
  for (int i = 0; i < runs; ++i) models.Palm(palm_in.data(), &p);
  *palm_ms = models.TakeModelMs() / runs;
  for (int i = 0; i < runs; ++i) models.Landmark(landmark_in.data(), &l);
  *landmark_ms = models.TakeModelMs() / runs;
}

std::vector<std::filesystem::path> RealVideos() {
  const std::filesystem::path dir = std::filesystem::path(DOASIDO_SHARED_DATA) / "videos";
  std::vector<std::filesystem::path> videos;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".mp4" || ext == ".avi") videos.push_back(e.path());
  }
  std::sort(videos.begin(), videos.end());
  return videos;
}

// One video's (or all videos') row: every palm, tracked, gated (native),
// the analysis pass, gated on wasm.
struct Row {
  Totals every, tracked, gated, wasm;
  double analysis_ms = 0;  // total over the samples
  int modelled = 0;
  void Add(const Row& r) {
    for (auto [from, to] : {std::pair{&r.every, &every}, {&r.tracked, &tracked},
                            {&r.gated, &gated}, {&r.wasm, &wasm}}) {
      to->samples += from->samples;
      to->hands += from->hands;
      to->model_ms += from->model_ms;
      to->detect_ms += from->detect_ms;
    }
    analysis_ms += r.analysis_ms;
    modelled += r.modelled;
  }
  void Print(const std::string& name, bool have_wasm) const {
    const double n = gated.samples;
    std::printf("%-20s %7d %6.2f | %10.2f | %10.2f | %10.2f %10.2f | %10.2f %7.0f%% | %10.2f | "
                "%6.1fx\n",
                name.c_str(), gated.samples, gated.hands / n, every.model_ms / n,
                tracked.model_ms / n, gated.model_ms / n, gated.detect_ms / n, analysis_ms / n,
                100.0 * modelled / n, have_wasm ? wasm.model_ms / n : 0.0,
                have_wasm ? wasm.model_ms / gated.model_ms : 0.0);
  }
};

int Main(int argc, char** argv) {
  const int per_video = argc > 1 ? std::atoi(argv[1]) : 40;
  LearnedDetectorConfig config;
  config.models = argc > 2 ? argv[2] : kModelsFull;
  if (argc > 3) config.no_hand_palm_every = std::atoi(argv[3]);
  if (argc > 4) config.no_hand_changed_fraction = std::atof(argv[4]);
  CheckConfig(config, "filters_hand_models_bench");
  const double unchanged_crop = argc > 5 ? std::atof(argv[5]) : 0.0;
  const std::string& models = config.models;
  const int palm_every = config.palm_every;
  HandLandmarker every_palm({.backend = kBackendNative, .models = models, .palm_every = 1});
  HandLandmarker native({.backend = kBackendNative, .models = models, .palm_every = palm_every});
  HandLandmarker gated({.backend = kBackendNative,
                        .models = models,
                        .palm_every = palm_every,
                        .unchanged_crop_fraction = unchanged_crop});
  PalmGate gate(config.no_hand_palm_every, config.no_hand_changed_fraction, {});
  std::string why;
  const bool have_wasm = WasmHandModelsAvailable(&why);
  std::unique_ptr<HandLandmarker> wasm;
  if (have_wasm) {
    wasm = std::make_unique<HandLandmarker>(
        HandLandmarkerOptions{.backend = kBackendWasm,
                              .models = models,
                              .palm_every = palm_every,
                              .unchanged_crop_fraction = unchanged_crop});
  }
  std::printf("MediaPipe Hands (%s models), CPU ms per sample (palm + landmark per hand), one "
              "core; tracked: palm detector every %d samples while a hand is tracked; gated: "
              "and with no hand tracked on every %d-th such sample where %.3f of the frame "
              "changed\n",
              models.c_str(), palm_every, config.no_hand_palm_every,
              config.no_hand_changed_fraction);
  std::printf("%-20s %7s %6s | %10s | %10s | %10s %10s | %10s %8s | %10s | %7s\n", "video",
              "samples", "hands", "every palm", "tracked", "gated", "gated all", "analysis",
              "modelled", "wasm gated", "speedup");
  Row all;
  for (const auto& video : RealVideos()) {
    const Sampled sampled = Samples(video, per_video);
    Row row;
    Measure(every_palm, sampled, nullptr, &row.every);
    Measure(native, sampled, nullptr, &row.tracked);
    Measure(gated, sampled, &gate, &row.gated);
    if (wasm) Measure(*wasm, sampled, &gate, &row.wasm);
    double analysis_ms = 0;
    Analysis(sampled, config, &analysis_ms, &row.modelled);
    row.analysis_ms = analysis_ms * row.gated.samples;
    row.Print(video.filename().string(), have_wasm);
    all.Add(row);
  }
  all.Print("all", have_wasm);
  if (unchanged_crop > 0) {
    std::printf("unchanged crops (at most %.3f of the pixels changed): %d landmark runs saved\n",
                unchanged_crop, gated.reused());
  }
  const Totals& all_native = all.gated;
  const Totals& all_wasm = all.wasm;
  if (!wasm) std::printf("(no wasm runtime to compare: %s)\n", why.c_str());
  std::printf("\nEach model alone, 30 runs: CPU ms per run\n%-15s %8s %8s\n", "", "native",
              "wasm");
  for (const char* pair : {kModelsFull, kModelsLite}) {
    double palm[2] = {0, 0}, landmark[2] = {0, 0};
    PerModel(*MakeNativeHandModels("", pair), 30, &palm[0], &landmark[0]);
    if (have_wasm) PerModel(*MakeWasmHandModels("", pair), 30, &palm[1], &landmark[1]);
    std::printf("%-15s %8.2f %8.2f\n%-15s %8.2f %8.2f\n", ("palm " + std::string(pair)).c_str(),
                palm[0], palm[1], ("landmark " + std::string(pair)).c_str(), landmark[0],
                landmark[1]);
  }
  if (wasm && all_wasm.hands != all_native.hands) {
    std::printf("note: the runtimes found %d and %d hands\n", all_native.hands, all_wasm.hands);
  }
  return 0;
}

}  // namespace
}  // namespace doasido::filters

int main(int argc, char** argv) { return doasido::filters::Main(argc, argv); }
