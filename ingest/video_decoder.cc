#include "ingest/video_decoder.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/error.h"

namespace doasido {

double AnalysisDownscale(int width, int height, int analysis_size) {
  const int longer = std::max(width, height);
  if (analysis_size <= 0 || longer < analysis_size) return 1.0;
  return static_cast<double>(longer) / static_cast<double>(analysis_size);
}

cv::Size AnalysisSize(int width, int height, int analysis_size) {
  const double factor = AnalysisDownscale(width, height, analysis_size);
  if (factor <= 1.0) return {width, height};
  // std::nearbyint rounds half to even in the default rounding mode, as
  // Python's round() does; PySceneDetect sizes its frames with round().
  const int w = static_cast<int>(std::nearbyint(width / factor));
  const int h = static_cast<int>(std::nearbyint(height / factor));
  return {std::max(1, w), std::max(1, h)};
}

VideoDecoder::VideoDecoder(const std::filesystem::path& path, const DecoderOptions& options)
    : path_(path), options_(options), capture_(std::make_unique<cv::VideoCapture>()) {
  const ErrorSite site{.clip = options.clip, .file = path.string()};
  if (!std::filesystem::exists(path)) {
    throw Error("video_open_failed", "video file does not exist", site);
  }
  if (!capture_->open(path.string(), cv::CAP_FFMPEG) || !capture_->isOpened()) {
    throw Error("video_open_failed",
                "FFmpeg could not open the file as a video (not a video, or truncated before "
                "its index)",
                site);
  }
  geometry_.full_width = static_cast<int>(capture_->get(cv::CAP_PROP_FRAME_WIDTH));
  geometry_.full_height = static_cast<int>(capture_->get(cv::CAP_PROP_FRAME_HEIGHT));
  geometry_.fps = capture_->get(cv::CAP_PROP_FPS);
  const double declared = capture_->get(cv::CAP_PROP_FRAME_COUNT);
  geometry_.declared_frames = declared > 0 ? static_cast<std::int64_t>(declared) : 0;
  if (geometry_.full_width <= 0 || geometry_.full_height <= 0) {
    throw Error("video_open_failed", "the video stream has no frame size", site);
  }
  const cv::Size size =
      AnalysisSize(geometry_.full_width, geometry_.full_height, options.analysis_size);
  geometry_.width = size.width;
  geometry_.height = size.height;
  geometry_.downscale =
      AnalysisDownscale(geometry_.full_width, geometry_.full_height, options.analysis_size);
  if (geometry_.fps > 0) {
    if (options_.first_frame == 0 && options_.first_s > 0) {
      options_.first_frame = std::llround(options_.first_s * geometry_.fps);
    }
    if (options_.last_frame < 0 && options_.last_s >= 0) {
      options_.last_frame = std::llround(options_.last_s * geometry_.fps);
    }
  }
  if (options_.first_frame < 0) {
    throw Error("bad_span", "first frame is negative",
                {.clip = options.clip, .file = path.string(), .field = "start_frame"});
  }
  // Grab (decode without colour conversion) up to the span: exact, unlike
  // seeking, which lands on key frames in some containers.
  while (next_index_ < options_.first_frame) {
    if (!capture_->grab()) {
      if (geometry_.declared_frames > 0 &&
          next_index_ < geometry_.declared_frames - options_.frame_count_tolerance) {
        ThrowTruncated(next_index_, "decoding stopped before the clip's first frame");
      }
      done_ = true;
      break;
    }
    ++next_index_;
  }
}

VideoDecoder::~VideoDecoder() = default;

void VideoDecoder::ThrowTruncated(std::int64_t frame, const std::string& why) const {
  std::string message = why + " (could not decode frame " + std::to_string(frame);
  if (geometry_.declared_frames > 0) {
    message += " of " + std::to_string(geometry_.declared_frames) + " declared";
  }
  message += "); the file is truncated or corrupt";
  throw Error(
      "truncated_video", message,
      {.clip = options_.clip, .file = path_.string(), .field = "frame " + std::to_string(frame)});
}

bool VideoDecoder::Next(AnalysisFrame* frame) {
  if (done_) return false;
  if (options_.last_frame >= 0 && next_index_ > options_.last_frame) {
    done_ = true;
    return false;
  }
  if (!capture_->read(full_) || full_.empty()) {
    done_ = true;
    if (geometry_.declared_frames > 0 &&
        next_index_ < geometry_.declared_frames - options_.frame_count_tolerance) {
      ThrowTruncated(next_index_, "decoding stopped early");
    }
    if (geometry_.declared_frames == 0 && delivered_ == 0) {
      ThrowTruncated(next_index_, "no frame could be decoded");
    }
    return false;
  }
  frame->index = next_index_;
  const double pos_ms = capture_->get(cv::CAP_PROP_POS_MSEC);
  frame->timestamp_s = pos_ms > 0 || next_index_ == 0 || geometry_.fps <= 0
                           ? pos_ms / 1000.0
                           : static_cast<double>(next_index_) / geometry_.fps;
  if (full_.cols != geometry_.full_width || full_.rows != geometry_.full_height) {
    throw Error("corrupt_video",
                "frame " + std::to_string(next_index_) + " is " + std::to_string(full_.cols) + "x" +
                    std::to_string(full_.rows) + ", the stream declares " +
                    std::to_string(geometry_.full_width) + "x" +
                    std::to_string(geometry_.full_height),
                {.clip = options_.clip,
                 .file = path_.string(),
                 .field = "frame " + std::to_string(next_index_)});
  }
  if (geometry_.width == full_.cols && geometry_.height == full_.rows) {
    frame->bgr = full_;
  } else {
    cv::resize(full_, frame->bgr, cv::Size(geometry_.width, geometry_.height), 0, 0,
               cv::INTER_LINEAR);
  }
  ++next_index_;
  ++delivered_;
  return true;
}

}  // namespace doasido
