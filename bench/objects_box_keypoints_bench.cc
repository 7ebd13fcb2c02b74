// What the objects' 2D box keypoints cost (objects/box_tracker.h), native:
// CPU milliseconds per run of the detector (SSD MobileNetV2, 300 x 300) and
// of the box-landmark model (224 x 224), and the whole pass (decoding at
// 640, resizing, crops, models, tracking) in CPU seconds (user + system of
// this process) per second of video; beside it, as the peer measured in the
// same run on the same frames, the hands stage's detection pass
// (hands/hand_detection.h, MediaPipe Hands, tracked, palm_every 10).
//
// Usage: objects_box_keypoints_bench [video=../shared/data/videos/02_cups.mp4]
//          [detect_every=10]
#include <sys/resource.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "filters/hand_landmarker.h"
#include "hands/hand_detection.h"
#include "objects/objects_in_video.h"

namespace {

double ProcessCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_utime.tv_usec * 1e-6 + u.ru_stime.tv_sec + u.ru_stime.tv_usec * 1e-6;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace doasido;
  const std::filesystem::path video =
      argc > 1 ? std::filesystem::path(argv[1])
               : std::filesystem::path(DOASIDO_SHARED_DATA) / "videos/02_cups.mp4";
  objects::BoxKeypointsConfig config;
  if (argc > 2) config.detect_every = std::atoi(argv[2]);
  objects::BoxTracker tracker(config, video.stem().string());
  double start = ProcessCpuSeconds();
  const objects::DetectedObjects d = objects::ObjectsInVideo(video, {}, config.max_side, tracker);
  const double objects_cpu = ProcessCpuSeconds() - start;
  const double video_s = d.fps > 0 ? d.frames.size() / d.fps : 0;
  int with_object = 0;
  for (const auto& f : d.frames) with_object += !f.empty();

  filters::HandLandmarker landmarker({.max_hands = 2, .palm_every = 10, .lost_search = 10});
  start = ProcessCpuSeconds();
  const hands::DetectedFrames h = hands::DetectVideo(video, {}, 640, landmarker);
  const double hands_cpu = ProcessCpuSeconds() - start;

  std::printf("%s: %zu frames, %.2f s of video, %d with an object\n", video.filename().c_str(),
              d.frames.size(), video_s, with_object);
  std::printf("  detector:       %4d runs, %7.2f ms per run\n", d.detector_runs,
              d.detector_runs ? d.detector_ms / d.detector_runs : 0.0);
  std::printf("  box landmarks:  %4d runs, %7.2f ms per run\n", d.landmark_runs,
              d.landmark_runs ? d.landmark_ms / d.landmark_runs : 0.0);
  std::printf("  objects pass:   %.2f CPU s = %.3f CPU s per video second (goal <= 0.5)\n", objects_cpu,
              video_s > 0 ? objects_cpu / video_s : 0.0);
  std::printf("  hands pass:     %.2f CPU s = %.3f CPU s per video second (peer)\n", hands_cpu,
              video_s > 0 ? hands_cpu / video_s : 0.0);
  std::printf("  ratio objects / hands: %.2f\n", hands_cpu > 0 ? objects_cpu / hands_cpu : 0.0);
  return 0;
}
