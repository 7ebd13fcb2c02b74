#include "hands/labelled_stills.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/error_codes.h"
#include "hands/packaged_image.h"
#include "video/video_decoder.h"

namespace doasido::hands {

cv::Mat DecodeFrame(const std::filesystem::path& video, int frame) {
  DecoderOptions span{.analysis_size = 0, .first_frame = frame, .last_frame = frame,
                      .clip = video.stem().string()};
  span.skip_loop_filter = false;
  VideoDecoder decoder(video, span);
  AnalysisFrame out;
  if (!decoder.Next(&out) || out.index != frame) {
    throw Error(kVideoTruncated, "no frame " + std::to_string(frame), {.file = video.string()});
  }
  return out.bgr.clone();
}

LabelledStill CloseUp(const cv::Mat& bgr, const LabelledFrame& labels, std::size_t hand,
                      double fill) {
  const auto [lo, hi] = VisibleBounds(labels.hands.at(hand));
  const Eigen::Vector2d centre = (lo + hi) / 2;
  const int side = std::min({static_cast<int>(std::lround((hi - lo).maxCoeff() / fill)),
                             bgr.cols, bgr.rows});
  const auto corner = [side](double c, int length) {
    return std::clamp(static_cast<int>(std::lround(c - side / 2.0)), 0, length - side);
  };
  const int x = corner(centre.x(), bgr.cols), y = corner(centre.y(), bgr.rows);
  LabelledStill still;
  still.kind = kStillCloseUp;
  still.image = bgr(cv::Rect(x, y, side, side)).clone();
  still.labels.frame = labels.frame;
  for (LabelledHand moved : labels.hands) {
    bool inside = true;
    for (int j = 0; j < kJoints; ++j) {
      moved.uv[j] -= Eigen::Vector2d(x, y);
      inside = inside && (!moved.visible[j] || (moved.uv[j].minCoeff() >= 0 &&
                                                moved.uv[j].x() < side && moved.uv[j].y() < side));
    }
    if (inside) still.labels.hands.push_back(moved);
  }
  return still;
}

LabelledStill Gray(const LabelledStill& still) {
  LabelledStill gray = still;
  gray.kind = still.kind + kGraySuffix;
  cv::cvtColor(still.image, gray.image, cv::COLOR_BGR2GRAY);
  return gray;
}

std::vector<LabelledStill> PhotoStills(const std::filesystem::path& labels_file) {
  const HandLabels labels = ReadHandLabels(labels_file);
  if (labels.frames.size() != 1 || labels.frames[0].frame != 0) {
    throw Error("bad_labels", "a photo has one frame, 0",
                {.file = labels_file.string(), .field = "frames"});
  }
  std::string why;
  const cv::Mat image = ReadPackagedImage(labels.video, &why);
  if (image.empty()) {
    throw Error("bad_labels",
                "cannot read the photo " + labels.video + ": " + why +
                    " (scripts/setup.sh --test installs it)",
                {.file = labels_file.string(), .field = "video"});
  }
  const LabelledStill photo{.kind = kStillPhoto, .name = labels_file.stem().string(),
                            .image = image, .labels = labels.frames[0]};
  return {photo, Gray(photo)};
}

std::vector<LabelledStill> StillsOfFrame(const cv::Mat& bgr, const LabelledFrame& labels,
                                         const std::string& name) {
  std::vector<LabelledStill> out;
  LabelledStill frame{.kind = kStillFrame, .name = name, .image = bgr, .labels = labels};
  out.push_back(frame);
  out.push_back(Gray(frame));
  for (std::size_t h = 0; h < labels.hands.size(); ++h) {
    LabelledStill close = CloseUp(bgr, labels, h);
    close.name = name + " hand " + std::to_string(h);
    out.push_back(close);
    out.push_back(Gray(close));
  }
  return out;
}

}  // namespace doasido::hands
