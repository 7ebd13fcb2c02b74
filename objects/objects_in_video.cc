#include "objects/objects_in_video.h"

#include <chrono>

namespace doasido::objects {

namespace {

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// What the models cost between two readings of their counters.
struct ModelClock {
  explicit ModelClock(const ObjectronModels& m)
      : models(m), detector_ms(m.detector_ms()), landmark_ms(m.landmark_ms()),
        detector_runs(m.detector_runs()), landmark_runs(m.landmark_runs()) {}
  void Into(DetectedObjects* out) const {
    out->detector_ms = models.detector_ms() - detector_ms;
    out->landmark_ms = models.landmark_ms() - landmark_ms;
    out->detector_runs = models.detector_runs() - detector_runs;
    out->landmark_runs = models.landmark_runs() - landmark_runs;
  }
  const ObjectronModels& models;
  double detector_ms, landmark_ms;
  int detector_runs, landmark_runs;
};

}  // namespace

DetectedObjects ObjectsInVideo(const std::filesystem::path& video, DecoderOptions span,
                               int max_side, BoxTracker& tracker,
                               const std::function<void(std::int64_t)>& progress,
                               const std::vector<SeedBox>& seeds, const HandsByFrame* hands) {
  const auto start = std::chrono::steady_clock::now();
  const ModelClock clock(tracker.models());
  span.analysis_size = max_side;
  span.skip_loop_filter = false;  // the models see these frames
  VideoDecoder decoder(video, span);
  const VideoGeometry& g = decoder.geometry();
  DetectedObjects out{.width = g.full_width, .height = g.full_height, .fps = g.fps,
                      .first_frame = decoder.first_frame()};
  tracker.Reset();
  AnalysisFrame frame;
  while (decoder.Next(&frame)) {
    if (out.frames.empty()) out.first_frame = frame.index;
    const double scale = static_cast<double>(out.width) / frame.bgr.cols;
    for (const SeedBox& seed : seeds) {
      if (seed.frame == frame.index) tracker.Seed(seed.category, seed.box);
    }
    if (hands != nullptr) {
      const auto it = hands->find(frame.index);
      if (it != hands->end()) tracker.NearHands(it->second);
    }
    out.frames.push_back(tracker.Track(frame.bgr, static_cast<int>(frame.index), scale));
    if (progress) progress(static_cast<std::int64_t>(out.frames.size()));
  }
  clock.Into(&out);
  out.seconds = Since(start);
  return out;
}

DetectedObjects ObjectsInImage(const cv::Mat& bgr, BoxTracker& tracker,
                               const std::vector<SeedBox>& seeds, const HandsByFrame* hands) {
  const auto start = std::chrono::steady_clock::now();
  const ModelClock clock(tracker.models());
  DetectedObjects out{.width = bgr.cols, .height = bgr.rows};
  tracker.Reset();
  for (const SeedBox& seed : seeds) {
    if (seed.frame == 0) tracker.Seed(seed.category, seed.box);
  }
  if (hands != nullptr && hands->count(0)) tracker.NearHands(hands->at(0));
  out.frames.push_back(tracker.Track(bgr, 0));
  clock.Into(&out);
  out.seconds = Since(start);
  return out;
}

}  // namespace doasido::objects
