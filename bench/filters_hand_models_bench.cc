// CPU time of MediaPipe Hands' two models per sample, the native runtime
// (our TFLite reader + XNNPACK, in process) against the reference (TFLite's
// WebAssembly runtime in Node), in the same run, on the same samples: every
// real sample video (../shared/data/videos) at analysis size, 5 samples per
// second, tracked from one sample to the next as the analysis pass does.
//
// Per sample: the models' CPU milliseconds (palm detector + landmark model
// per hand; the calling thread's for native, the Node process's for wasm)
// and, for native, the whole Detect() (with the crops' resampling and the
// post-processing) on this thread.
//
// Usage: filters_hand_models_bench [samples per video=40]
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "filters/hand_landmarker.h"
#include "filters/hand_models.h"
#include "video/video_decoder.h"

namespace doasido::filters {
namespace {

double ThreadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

std::vector<cv::Mat> Samples(const std::filesystem::path& video, int count) {
  VideoDecoder decoder(video, DecoderOptions{});
  const double fps = decoder.geometry().fps > 0 ? decoder.geometry().fps : 30;
  const int every = std::max(1, static_cast<int>(std::lround(fps / 5)));
  std::vector<cv::Mat> samples;
  AnalysisFrame frame;
  for (int i = 0; static_cast<int>(samples.size()) < count && decoder.Next(&frame); ++i) {
    if (i % every == 0) samples.push_back(frame.bgr.clone());
  }
  return samples;
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
  const std::filesystem::path dir = std::filesystem::path(DOASIDO_SHARED_DATA) / "videos";
  HandLandmarker native({.backend = kBackendNative});
  std::string why;
  const bool have_wasm = WasmHandModelsAvailable(&why);
  std::unique_ptr<HandLandmarker> wasm;
  if (have_wasm) wasm = std::make_unique<HandLandmarker>(HandLandmarkerOptions{.backend = kBackendWasm});
  std::vector<std::filesystem::path> videos;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".mp4" || ext == ".avi") videos.push_back(e.path());
  }
  std::sort(videos.begin(), videos.end());
  std::printf("MediaPipe Hands, CPU ms per sample (palm + landmark per hand), one core\n");
  std::printf("%-20s %7s %6s | %12s %12s | %12s | %7s\n", "video", "samples", "hands",
              "native model", "native all", "wasm model", "speedup");
  Totals all_native, all_wasm;
  for (const auto& video : videos) {
    const std::vector<cv::Mat> samples = Samples(video, per_video);
    Totals n, w;
    Measure(native, samples, &n);
    if (wasm) Measure(*wasm, samples, &w);
    std::printf("%-20s %7d %6.2f | %12.2f %12.2f | %12.2f | %6.1fx\n",
                video.filename().string().c_str(), n.samples, double(n.hands) / n.samples,
                n.model_ms / n.samples, n.detect_ms / n.samples,
                wasm ? w.model_ms / w.samples : 0.0, wasm ? w.model_ms / n.model_ms : 0.0);
    for (auto [from, to] : {std::pair{&n, &all_native}, std::pair{&w, &all_wasm}}) {
      to->samples += from->samples;
      to->hands += from->hands;
      to->model_ms += from->model_ms;
      to->detect_ms += from->detect_ms;
    }
  }
  std::printf("%-20s %7d %6.2f | %12.2f %12.2f | %12.2f | %6.1fx\n", "all",
              all_native.samples, double(all_native.hands) / all_native.samples,
              all_native.model_ms / all_native.samples, all_native.detect_ms / all_native.samples,
              wasm ? all_wasm.model_ms / all_wasm.samples : 0.0,
              wasm ? all_wasm.model_ms / all_native.model_ms : 0.0);
  if (!wasm) std::printf("(no wasm runtime to compare: %s)\n", why.c_str());
  double palm[2] = {0, 0}, landmark[2] = {0, 0};
  PerModel(*MakeNativeHandModels(""), 30, &palm[0], &landmark[0]);
  if (have_wasm) PerModel(*MakeWasmHandModels(""), 30, &palm[1], &landmark[1]);
  std::printf("\nEach model alone, 30 runs: CPU ms per run\n%-10s %8s %8s\n", "", "native",
              "wasm");
  std::printf("%-10s %8.2f %8.2f\n%-10s %8.2f %8.2f\n", "palm", palm[0], palm[1], "landmark",
              landmark[0], landmark[1]);
  if (wasm && all_wasm.hands != all_native.hands) {
    std::printf("note: the runtimes found %d and %d hands\n", all_native.hands, all_wasm.hands);
  }
  return 0;
}

}  // namespace
}  // namespace doasido::filters

int main(int argc, char** argv) { return doasido::filters::Main(argc, argv); }
