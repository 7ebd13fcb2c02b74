// What the objects' 2D box keypoints cost (objects/box_tracker.h), native:
// CPU milliseconds per run of the detector (SSD MobileNetV2, 300 x 300) and
// of the box-landmark model (224 x 224), and the whole pass (decoding at
// 640, resizing, crops, models, tracking) in CPU seconds (user + system of
// this process) per second of video; beside it, as the peer measured in the
// same run on the same frames, the hands stage's detection pass
// (hands/hand_detection.h, MediaPipe Hands, tracked, palm_every 10).
//
// Usage: objects_box_keypoints_bench [video=../shared/data/videos/02_cups.mp4]
//          [detect_every=10] [FRAME:X,Y,W,H ...] (cup seeds, as doasido objects --seed;
//          the prompted tracks' 2D follower's runs and CPU ms are printed too)
//        objects_box_keypoints_bench labels [labels.json=bench/object_labels/02_cups.json]
//          the box-landmark model alone against the hand-made cup labels: on
//          every labelled frame each labelled cup is seeded as a person would
//          box it (its height tall, 0.8 of it wide) and the model's centre and
//          top / bottom face centres are compared with the labelled centre and
//          upper / lower rim centres (px, and as a fraction of the cup's height).
//        objects_box_keypoints_bench find [labels.json] [held_from=200] [sizes=1.6,2.4]
//          how the cups are found with no seed, on labelled frames before
//          held_from (tuning) and from it on (held back): the 2D detector's
//          best cup / mug score on each labelled cup at any threshold; the
//          boxes tried beside the hands (objects/hand_proposals.h, the hands
//          from the hand landmarker) on each labelled frame alone; and the
//          whole video tracked with the detector and the hand proposals.
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/config.h"
#include "core/file_text.h"
#include "filters/hand_landmarker.h"
#include "hands/hand_detection.h"
#include "objects/box_detector.h"
#include "objects/objects_in_video.h"
#include "testing/real_footage.h"

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

// The labelled video: "video_source" (a package's file, testing/real_footage.h)
// or "video_name" in ../shared/data/videos.
std::filesystem::path LabelledVideo(const Json& labels) {
  if (labels.contains("video_source")) {
    return doasido::testing::ResolveRealFootage(labels.at("video_source").get<std::string>(), DOASIDO_SHARED_DATA,
                                                std::filesystem::temp_directory_path() / "doasido-object-labels");
  }
  return std::filesystem::path(DOASIDO_SHARED_DATA) / "videos" / labels.at("video_name").get<std::string>();
}

// The box a person would draw about a cup from its rims (upper, lower): the
// cup's height long, 0.8 of it wide, along its axis, 5 % beyond each rim.
cv::Rect2d SeedBoxOf(const Eigen::Vector2d& up, const Eigen::Vector2d& low) {
  const double h = (low - up).norm();
  const Eigen::Vector2d a = (low - up) / h, n(-a.y(), a.x());
  double x1 = 1e18, y1 = 1e18, x2 = -1e18, y2 = -1e18;
  for (const Eigen::Vector2d& p : {Eigen::Vector2d(up - 0.05 * h * a + 0.4 * h * n), Eigen::Vector2d(up - 0.05 * h * a - 0.4 * h * n),
                                   Eigen::Vector2d(low + 0.05 * h * a + 0.4 * h * n), Eigen::Vector2d(low + 0.05 * h * a - 0.4 * h * n)}) {
    x1 = std::min(x1, p.x()), y1 = std::min(y1, p.y()), x2 = std::max(x2, p.x()), y2 = std::max(y2, p.y());
  }
  return {x1, y1, x2 - x1, y2 - y1};
}

int Labels(const std::filesystem::path& path) {
  using namespace doasido;
  const Json labels = Json::parse(ReadFileOrThrow(path, "io", "cannot read the labels"));
  const std::filesystem::path video = LabelledVideo(labels);
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
      seeds.push_back({.frame = f, .category = "cup", .box = SeedBoxOf(Point(cup.at("upper")), Point(cup.at("lower")))});
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


struct Cup {
  Eigen::Vector2d centre, upper, lower;
  double height;
};
std::vector<Cup> CupsOf(const Json& frame) {
  std::vector<Cup> cups;
  for (const Json& c : frame.at("cups")) {
    const Eigen::Vector2d up = Point(c.at("upper")), low = Point(c.at("lower"));
    cups.push_back({Point(c.at("centre")), up, low, (low - up).norm()});
  }
  return cups;
}

// Found / labelled cups and boxes on no labelled cup, per part of the labels.
struct Tally {
  int cups = 0, found = 0, stray = 0;
  std::vector<double> centre_px;
};
// Each labelled cup is found by the observation nearest it within half its height.
void Score(const std::vector<Cup>& cups, const std::vector<doasido::objects::ObjectObservation>& seen,
           Tally* t) {
  std::vector<bool> used(seen.size(), false);
  for (const Cup& c : cups) {
    ++t->cups;
    int best = -1;
    for (size_t i = 0; i < seen.size(); ++i) {
      const double d = (seen[i].keypoints_2d[0] - c.centre).norm();
      if (!used[i] && d <= 0.5 * c.height && (best < 0 || d < (seen[best].keypoints_2d[0] - c.centre).norm())) {
        best = static_cast<int>(i);
      }
    }
    if (best < 0) continue;
    used[best] = true;
    ++t->found;
    t->centre_px.push_back((seen[best].keypoints_2d[0] - c.centre).norm());
  }
  for (bool u : used) t->stray += !u;
}

void PrintTally(const char* what, const Tally& a, const Tally& b) {
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  std::printf("  %-34s tuning %2d/%2d found (%d stray boxes, centre median %4.1f px); held back %2d/%2d (%d stray, %4.1f px)\n",
              what, a.found, a.cups, a.stray, median(a.centre_px), b.found, b.cups, b.stray, median(b.centre_px));
}

// "1.6,2.4" -> {1.6, 2.4}.
std::vector<double> Sizes(const std::string& text) {
  std::vector<double> out;
  for (size_t at = 0; at < text.size();) {
    size_t end = text.find(',', at);
    if (end == std::string::npos) end = text.size();
    out.push_back(std::atof(text.substr(at, end - at).c_str()));
    at = end + 1;
  }
  return out;
}

int Find(const std::filesystem::path& path, int held_from, const std::vector<double>& sizes) {
  using namespace doasido;
  const Json labels = Json::parse(ReadFileOrThrow(path, "io", "cannot read the labels"));
  const std::filesystem::path video = LabelledVideo(labels);
  // The hands, as the hands stage finds them.
  filters::HandLandmarker landmarker({.max_hands = 2, .palm_every = 10, .lost_search = 10});
  const hands::DetectedFrames h = hands::DetectVideo(video, {}, 640, landmarker);
  objects::HandsByFrame by_frame;
  for (size_t i = 0; i < h.frames.size(); ++i) {
    auto& list = by_frame[h.first_frame + static_cast<std::int64_t>(i)];
    for (const hands::HandObservation& o : h.frames[i]) {
      objects::HandPoints2d p;
      for (int k = 0; k < objects::kHandPoints; ++k) p[k] = o.uv[k];
      list.push_back(p);
    }
  }
  objects::BoxKeypointsConfig config;
  config.categories = {"cup"};
  if (!sizes.empty()) config.hand_proposal_sizes = sizes;
  objects::ObjectronModels models({"cup"}, video.stem().string());
  Tally det[2][3], alone[2], tracked[2];
  const double thresholds[3] = {0.5, 0.2, 0.05};
  int near_hand[2] = {0, 0};
  config.hand_proposals = true;
  config.hand_proposal_every = 1;
  objects::BoxTracker single(config, video.stem().string());
  for (const Json& frame : labels.at("frames")) {
    const std::int64_t f = frame.at("frame");
    const int part = f >= held_from ? 1 : 0;
    const std::vector<Cup> cups = CupsOf(frame);
    VideoDecoder decoder(video, {.analysis_size = 640, .first_frame = f, .last_frame = f, .skip_loop_filter = false});
    AnalysisFrame af;
    if (!decoder.Next(&af)) return 1;
    const double to_input = static_cast<double>(decoder.geometry().full_width) / af.bgr.cols;
    cv::Mat rgb;
    cv::cvtColor(af.bgr, rgb, cv::COLOR_BGR2RGB);
    std::vector<float> input;
    objects::DetectorInput(rgb, &input);
    objects::DetectorOutput out;
    models.Detect(input.data(), &out);
    for (int k = 0; k < 3; ++k) {
      std::vector<objects::ObjectObservation> seen;
      for (const objects::DetectedBox& b : objects::DecodeDetections(out, models.labels(), {"cup"}, thresholds[k], 0.5, 20)) {
        objects::ObjectObservation o;
        o.keypoints_2d[0] = {(b.box.x + b.box.width / 2) * rgb.cols * to_input, (b.box.y + b.box.height / 2) * rgb.rows * to_input};
        seen.push_back(o);
      }
      Score(cups, seen, &det[part][k]);
    }
    for (const Cup& c : cups) {
      for (const objects::HandPoints2d& hand : by_frame[f]) {
        const Eigen::Vector2d grasp = (hand[4] + hand[8] + hand[12]) / 3.0;
        if ((grasp - c.centre).norm() < c.height) {
          ++near_hand[part];
          break;
        }
      }
    }
    objects::HandsByFrame one{{f, by_frame[f]}};
    const objects::DetectedObjects d =
        objects::ObjectsInVideo(video, {.first_frame = f, .last_frame = f}, config.max_side, single, {}, {}, &one);
    Score(cups, d.frames.at(0), &alone[part]);
  }
  config.hand_proposal_every = objects::BoxKeypointsConfig{}.hand_proposal_every;
  objects::BoxTracker tracker(config, video.stem().string());
  const double start = ProcessCpuSeconds();
  const objects::DetectedObjects all = objects::ObjectsInVideo(video, {}, config.max_side, tracker, {}, {}, &by_frame);
  const double cpu = ProcessCpuSeconds() - start;
  for (const Json& frame : labels.at("frames")) {
    const std::int64_t f = frame.at("frame");
    Score(CupsOf(frame), all.frames.at(f - all.first_frame), &tracked[f >= held_from ? 1 : 0]);
  }
  std::printf("%s (%s): labelled frames before %d tuning, from %d held back; %d / %d labelled cups within a cup height of a hand's grasp point\n",
              path.filename().c_str(), video.filename().c_str(), held_from, held_from, near_hand[0], near_hand[1]);
  for (int k = 0; k < 3; ++k) {
    char what[64];
    std::snprintf(what, sizeof what, "detector, cup/mug score >= %.2f:", thresholds[k]);
    PrintTally(what, det[0][k], det[1][k]);
  }
  PrintTally("hand proposals, each frame alone:", alone[0], alone[1]);
  PrintTally("tracked (detector + hands):", tracked[0], tracked[1]);
  const double video_s = all.fps > 0 ? all.frames.size() / all.fps : 0;
  std::printf("  tracked pass: %d detector runs, %d landmark runs, %.2f CPU s = %.3f per video second\n",
              all.detector_runs, all.landmark_runs, cpu, video_s > 0 ? cpu / video_s : 0.0);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace doasido;
  if (argc > 1 && std::string(argv[1]) == "find") {
    return Find(argc > 2 ? std::filesystem::path(argv[2])
                         : std::filesystem::path(DOASIDO_SOURCE_DIR) / "bench/object_labels/02_cups.json",
                argc > 3 ? std::atoi(argv[3]) : 200, argc > 4 ? Sizes(argv[4]) : std::vector<double>{});
  }
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
  std::printf("  2D follower:    %4d runs, %7.2f ms per run (prompted tracks)\n", tracker.follower_runs(),
              tracker.follower_runs() ? tracker.follower_ms() / tracker.follower_runs() : 0.0);
  std::printf("  objects pass:   %.2f CPU s = %.3f CPU s per video second (goal <= 0.5)\n", objects_cpu,
              video_s > 0 ? objects_cpu / video_s : 0.0);
  std::printf("  hands pass:     %.2f CPU s = %.3f CPU s per video second (peer)\n", hands_cpu,
              video_s > 0 ? hands_cpu / video_s : 0.0);
  std::printf("  ratio objects / hands: %.2f\n", hands_cpu > 0 ? objects_cpu / hands_cpu : 0.0);
  return 0;
}
