#include "hands/hand_detection.h"

#include <chrono>

namespace doasido::hands {
namespace {

FrameObservations Observe(const std::vector<filters::LandmarkedHand>& hands, double scale,
                          int width, int height) {
  FrameObservations out;
  for (const auto& h : hands) out.push_back(FromLandmarked(h, scale, width, height));
  return out;
}

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

DetectedFrames DetectVideo(const std::filesystem::path& video, DecoderOptions span, int max_side,
                           filters::HandLandmarker& landmarker,
                           const std::function<void(std::int64_t)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  span.analysis_size = max_side;
  // The models see these frames: keep the deblocking filter on.
  span.skip_loop_filter = false;
  VideoDecoder decoder(video, span);
  const VideoGeometry& g = decoder.geometry();
  DetectedFrames out;
  out.width = g.full_width;
  out.height = g.full_height;
  out.fps = g.fps;
  out.first_frame = decoder.first_frame();
  landmarker.Reset();
  AnalysisFrame frame;
  while (decoder.Next(&frame)) {
    if (out.frames.empty()) out.first_frame = frame.index;
    const double scale = static_cast<double>(out.width) / frame.bgr.cols;
    out.frames.push_back(Observe(landmarker.Detect(frame.bgr), scale, out.width, out.height));
    out.model_seconds += landmarker.last_ms() / 1000.0;
    if (progress) progress(static_cast<std::int64_t>(out.frames.size()));
  }
  out.seconds = Since(start);
  return out;
}

DetectedFrames DetectImage(const cv::Mat& bgr, filters::HandLandmarker& landmarker) {
  const auto start = std::chrono::steady_clock::now();
  DetectedFrames out;
  out.width = bgr.cols;
  out.height = bgr.rows;
  out.frames.push_back(Observe(landmarker.DetectStill(bgr), 1.0, out.width, out.height));
  out.model_seconds = landmarker.last_ms() / 1000.0;
  out.seconds = Since(start);
  return out;
}

}  // namespace doasido::hands
