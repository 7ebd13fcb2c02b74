// What the objects' 2D box keypoints cost (objects/box_tracker.h), native:
// CPU milliseconds per run of the detector (SSD MobileNetV2, 300 x 300) and
// of the box-landmark model (224 x 224), and the whole pass (decoding at
// 640, resizing, crops, models, tracking) in CPU seconds (user + system of
// this process) per second of video; beside it, as the peer measured in the
// same run on the same frames, the hands stage's detection pass
// (hands/hand_detection.h, MediaPipe Hands, tracked, palm_every 10).
//
// Usage: objects_box_keypoints_bench [video=../shared/data/videos/02_cups.mp4]
//          [detect_every=10] [FRAME:X,Y,W,H ...] (cup seeds, as doasido objects --seed)
//        objects_box_keypoints_bench labels [labels.json=bench/object_labels/02_cups.json]
//          the box-landmark model alone against the hand-made cup labels: on
//          every labelled frame each labelled cup is seeded as a person would
//          box it (its height tall, 0.8 of it wide) and the model's centre and
//          top / bottom face centres are compared with the labelled centre and
//          upper / lower rim centres (px, and as a fraction of the cup's height).
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <opencv2/core.hpp>

#include "core/config.h"
#include "core/file_text.h"
#include "filters/hand_landmarker.h"
#include "hands/hand_detection.h"
#include "objects/objects_in_video.h"

namespace {

double ProcessCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_utime.tv_usec * 1e-6 + u.ru_stime.tv_sec + u.ru_stime.tv_usec * 1e-6;
}

using doasido::Json;

Eigen::Vector2d Point(const Json& xy) { return {xy.at(0).get<double>(), xy.at(1).get<double>()}; }

Eigen::Vector2d FaceCentre(const doasido::objects::ObjectObservation& o, bool top) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (int k = 1; k < doasido::objects::kBoxKeypoints; ++k) {
    if ((((k - 1) & 2) != 0) == top) sum += o.keypoints_2d[k] / 4;
  }
  return sum;
}

int Labels(const std::filesystem::path& path) {
  using namespace doasido;
  const Json labels = Json::parse(ReadFileOrThrow(path, "io", "cannot read the labels"));
  const std::filesystem::path video = std::filesystem::path(DOASIDO_SHARED_DATA) / "videos" /
                                      labels.at("video_name").get<std::string>();
  objects::BoxKeypointsConfig config;
  config.categories = {"cup"};
  objects::BoxTracker tracker(config, video.stem().string());
  std::vector<double> centre, top, bottom, relative;
  int cups = 0, missed = 0;
  for (const Json& frame : labels.at("frames")) {
    const std::int64_t f = frame.at("frame");
    std::vector<objects::SeedBox> seeds;
    for (const Json& cup : frame.at("cups")) {
      ++cups;
      const Eigen::Vector2d up = Point(cup.at("upper")), low = Point(cup.at("lower"));
      const double h = low.y() - up.y();
      seeds.push_back({.frame = f, .category = "cup",
                       .box = cv::Rect2d(up.x() - 0.4 * h, up.y() - 0.05 * h, 0.8 * h, 1.1 * h)});
    }
    const objects::DetectedObjects d =
        objects::ObjectsInVideo(video, {.first_frame = f, .last_frame = f}, config.max_side, tracker, {}, seeds);
    for (const Json& cup : frame.at("cups")) {
      const objects::ObjectObservation* best = nullptr;
      for (const auto& o : d.frames.at(0)) {
        if (!best || (o.keypoints_2d[0] - Point(cup.at("centre"))).norm() <
                         (best->keypoints_2d[0] - Point(cup.at("centre"))).norm()) {
          best = &o;
        }
      }
      const double h = (Point(cup.at("upper")) - Point(cup.at("lower"))).norm();
      if (!best || (best->keypoints_2d[0] - Point(cup.at("centre"))).norm() > 0.5 * h) {
        ++missed;
        continue;
      }
      centre.push_back((best->keypoints_2d[0] - Point(cup.at("centre"))).norm());
      top.push_back((FaceCentre(*best, true) - Point(cup.at("upper"))).norm());
      bottom.push_back((FaceCentre(*best, false) - Point(cup.at("lower"))).norm());
      relative.push_back(centre.back() / h);
    }
  }
  const auto mean = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / v.size();
  };
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  std::printf("%s: %zu frames, %d labelled cups, %d without a box (presence < 0.99 on the seeded crop)\n",
              path.filename().c_str(), labels.at("frames").size(), cups, missed);
  std::printf("  centre:      mean %5.1f px, median %5.1f px (mean %.3f of the cup's height)\n", mean(centre),
              median(centre), mean(relative));
  std::printf("  top face:    mean %5.1f px, median %5.1f px (against the upper rim's centre)\n", mean(top),
              median(top));
  std::printf("  bottom face: mean %5.1f px, median %5.1f px (against the lower rim's centre)\n", mean(bottom),
              median(bottom));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace doasido;
  if (argc > 1 && std::string(argv[1]) == "labels") {
    return Labels(argc > 2 ? std::filesystem::path(argv[2])
                           : std::filesystem::path(DOASIDO_SOURCE_DIR) / "bench/object_labels/02_cups.json");
  }
  const std::filesystem::path video =
      argc > 1 ? std::filesystem::path(argv[1])
               : std::filesystem::path(DOASIDO_SHARED_DATA) / "videos/02_cups.mp4";
  objects::BoxKeypointsConfig config;
  if (argc > 2) config.detect_every = std::atoi(argv[2]);
  std::vector<objects::SeedBox> seeds;
  for (int i = 3; i < argc; ++i) {
    objects::SeedBox seed;
    long long frame = 0;
    double x = 0, y = 0, w = 0, h = 0;
    if (std::sscanf(argv[i], "%lld:%lf,%lf,%lf,%lf", &frame, &x, &y, &w, &h) != 5) return 2;
    seed.frame = frame;
    seed.box = cv::Rect2d(x, y, w, h);
    seeds.push_back(seed);
  }
  objects::BoxTracker tracker(config, video.stem().string());
  double start = ProcessCpuSeconds();
  const objects::DetectedObjects d = objects::ObjectsInVideo(video, {}, config.max_side, tracker, {}, seeds);
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
