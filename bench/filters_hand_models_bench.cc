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
//                hand is tracked (the analysis pass's default), both runtimes;
//   analysis:    as the analysis pass runs them (LearnedHandDetector with
//                its defaults: tracked, and still samples keep the last
//                hands without a model run): model ms per sample of the
//                pass, and the share of samples the models saw.
//
// The model pair (full or lite) is the second argument; each model alone
// is timed for both pairs.
//
// Usage: filters_hand_models_bench [samples per video=40] [full|lite=full]
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
  std::vector<cv::Mat> frames;
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
    if (i % every == 0) out.frames.push_back(frame.bgr.clone());
  }
  return out;
}

// The analysis pass's detector on the samples (it sees only the sample
// frames, which is all it looks at): model CPU ms per sample, and how many
// samples ran the models.
void Analysis(const Sampled& s, const std::string& models, double* ms_per_sample,
              int* model_samples) {
  LearnedDetectorConfig config;
  config.models = models;
  LearnedHandDetector detector(config, "");
  detector.Begin(s.geometry);
  AnalysisFrame frame;
  for (std::size_t i = 0; i < s.frames.size(); ++i) {
    FrameContext context;
    frame.index = static_cast<std::int64_t>(i) * s.every;
    frame.bgr = s.frames[i];
    context.frame = &frame;
    context.ordinal = frame.index;
    cv::cvtColor(frame.bgr, context.gray, cv::COLOR_BGR2GRAY);
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

void Measure(HandLandmarker& landmarker, const std::vector<cv::Mat>& samples, Totals* t) {
  landmarker.Reset();
  for (const cv::Mat& frame : samples) {
    const double start = ThreadCpuMs();
    t->hands += static_cast<int>(landmarker.Detect(frame).size());
    t->detect_ms += ThreadCpuMs() - start;
    t->model_ms += landmarker.last_ms();
    ++t->samples;
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

int Main(int argc, char** argv) {
  const int per_video = argc > 1 ? std::atoi(argv[1]) : 40;
  const std::string models = argc > 2 ? argv[2] : kModelsFull;
  const std::filesystem::path dir = std::filesystem::path(DOASIDO_SHARED_DATA) / "videos";
  const int palm_every = LearnedDetectorConfig{}.palm_every;
  HandLandmarker every_palm({.backend = kBackendNative, .models = models, .palm_every = 1});
  HandLandmarker native({.backend = kBackendNative, .models = models, .palm_every = palm_every});
  std::string why;
  const bool have_wasm = WasmHandModelsAvailable(&why);
  std::unique_ptr<HandLandmarker> wasm;
  if (have_wasm) {
    wasm = std::make_unique<HandLandmarker>(
        HandLandmarkerOptions{.backend = kBackendWasm, .models = models, .palm_every = palm_every});
  }
  std::vector<std::filesystem::path> videos;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".mp4" || ext == ".avi") videos.push_back(e.path());
  }
  std::sort(videos.begin(), videos.end());
  std::printf("MediaPipe Hands (%s models), CPU ms per sample (palm + landmark per hand), one "
              "core; tracked: palm detector every %d samples while a hand is tracked\n",
              models.c_str(), palm_every);
  std::printf("%-20s %7s %6s | %10s | %10s %10s | %10s %7s | %10s | %7s\n", "video", "samples",
              "hands", "every palm", "tracked", "tracked all", "analysis", "modelled", "wasm trkd",
              "speedup");
  Totals all_every, all_native, all_wasm;
  double all_analysis = 0;
  int all_modelled = 0;
  const auto add = [](const Totals& from, Totals* to) {
    to->samples += from.samples;
    to->hands += from.hands;
    to->model_ms += from.model_ms;
    to->detect_ms += from.detect_ms;
  };
  for (const auto& video : videos) {
    const Sampled sampled = Samples(video, per_video);
    const std::vector<cv::Mat>& samples = sampled.frames;
    Totals e, n, w;
    Measure(every_palm, samples, &e);
    Measure(native, samples, &n);
    if (wasm) Measure(*wasm, samples, &w);
    double analysis_ms = 0;
    int modelled = 0;
    Analysis(sampled, models, &analysis_ms, &modelled);
    std::printf("%-20s %7d %6.2f | %10.2f | %10.2f %10.2f | %10.2f %6.0f%% | %10.2f | %6.1fx\n",
                video.filename().string().c_str(), n.samples, double(n.hands) / n.samples,
                e.model_ms / e.samples, n.model_ms / n.samples, n.detect_ms / n.samples,
                analysis_ms, 100.0 * modelled / n.samples, wasm ? w.model_ms / w.samples : 0.0,
                wasm ? w.model_ms / n.model_ms : 0.0);
    add(e, &all_every);
    add(n, &all_native);
    add(w, &all_wasm);
    all_analysis += analysis_ms * n.samples;
    all_modelled += modelled;
  }
  const double ns = all_native.samples;
  std::printf("%-20s %7d %6.2f | %10.2f | %10.2f %10.2f | %10.2f %6.0f%% | %10.2f | %6.1fx\n",
              "all", all_native.samples, all_native.hands / ns, all_every.model_ms / ns,
              all_native.model_ms / ns, all_native.detect_ms / ns, all_analysis / ns,
              100.0 * all_modelled / ns, wasm ? all_wasm.model_ms / all_wasm.samples : 0.0,
              wasm ? all_wasm.model_ms / all_native.model_ms : 0.0);
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
