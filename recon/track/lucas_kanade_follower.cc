#include "recon/track/lucas_kanade_follower.h"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <opencv2/videoio.hpp>

#include "core/error.h"
#include "core/stage_progress.h"

namespace doasido::recon {

PointFollower FollowWithLucasKanade(std::vector<cv::Mat> gray, const LucasKanadeOptions& o) {
  auto frames = std::make_shared<std::vector<cv::Mat>>(std::move(gray));
  return [frames, o](int k, const std::vector<Vec2>& points) {
    std::vector<PointFollow> out;
    for (const Vec2& p : points) out.push_back({p, p, false});
    if (points.empty() || k + 1 >= static_cast<int>(frames->size())) return out;
    std::vector<cv::Point2f> from, to, back;
    for (const Vec2& p : points) from.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
    std::vector<std::uint8_t> ok, ok_back;
    std::vector<float> error;
    const cv::Size window(o.window_px, o.window_px);
    cv::calcOpticalFlowPyrLK((*frames)[k], (*frames)[k + 1], from, to, ok, error, window,
                             o.pyramid_levels);
    cv::calcOpticalFlowPyrLK((*frames)[k + 1], (*frames)[k], to, back, ok_back, error, window,
                             o.pyramid_levels);
    for (size_t i = 0; i < points.size(); ++i) {
      const double fb = std::hypot(back[i].x - from[i].x, back[i].y - from[i].y);
      if (!ok[i] || !ok_back[i] || fb > o.max_fb_error_px) continue;
      out[i].to = Vec2(to[i].x, to[i].y);
      out[i].found = true;
    }
    return out;
  };
}

std::vector<cv::Mat> ReadGrayFrames(const std::filesystem::path& video, std::int64_t first,
                                    int count, int width, int height) {
  cv::VideoCapture capture(video.string(), cv::CAP_FFMPEG);
  if (!capture.isOpened()) {
    throw Error("video_unreadable", "OpenCV cannot open the clip's video for point following",
                {.file = video.string()});
  }
  if (first > 0) capture.set(cv::CAP_PROP_POS_FRAMES, static_cast<double>(first));
  std::vector<cv::Mat> out;
  cv::Mat bgr, gray;
  while (static_cast<int>(out.size()) < count && capture.read(bgr)) {
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    if (gray.cols != width || gray.rows != height) {
      cv::resize(gray, gray, cv::Size(width, height), 0, 0, cv::INTER_AREA);
    }
    out.push_back(gray.clone());
    ReportStageProgress();
  }
  if (static_cast<int>(out.size()) < count) {
    throw Error("video_unreadable",
                "the video ends after " + std::to_string(out.size()) + " of the bundle's " +
                    std::to_string(count) + " frames",
                {.file = video.string()});
  }
  return out;
}

}  // namespace doasido::recon
