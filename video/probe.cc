#include "video/probe.h"

#include <cmath>

#include <opencv2/videoio.hpp>

#include "core/config_check.h"
#include "core/permanent_error.h"

namespace doasido::video {

void CheckConfig(const ProbeConfig& c, const std::string& section) {
  RequireInRange(section, "vfr_tolerance", c.vfr_tolerance, 0, 1);
  RequireInRange(section, "max_missing_fraction", c.max_missing_fraction, 0, 1);
}

VideoInfo ProbeVideo(const std::filesystem::path& path, const ProbeConfig& config) {
  const ErrorSite site{.file = path.string()};
  if (path.string().find("://") != std::string::npos) {
    throw PermanentError("video_not_downloaded",
                         "the video is a URL that was not downloaded (put the `download` stage "
                         "before probe in the pipeline)",
                         site);
  }
  if (!std::filesystem::exists(path)) throw Error("video_missing", "no such file", site);
  cv::VideoCapture cap(path.string(), cv::CAP_FFMPEG);
  if (!cap.isOpened()) {
    throw Error("video_unreadable", "FFmpeg cannot open it (corrupt, truncated or not a video)",
                site);
  }
  VideoInfo info;
  info.width = static_cast<int>(cap.get(cv::CAP_PROP_FRAME_WIDTH));
  info.height = static_cast<int>(cap.get(cv::CAP_PROP_FRAME_HEIGHT));
  info.fps = cap.get(cv::CAP_PROP_FPS);
  info.rotation_deg = static_cast<int>(cap.get(cv::CAP_PROP_ORIENTATION_META));
  const int fourcc = static_cast<int>(cap.get(cv::CAP_PROP_FOURCC));
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xFF);
    if (c > ' ') info.codec += c;
  }
  const auto declared = static_cast<std::int64_t>(cap.get(cv::CAP_PROP_FRAME_COUNT));
  if (info.width <= 0 || info.height <= 0) {
    throw Error("video_unreadable", "no video stream with a frame size", site);
  }
  if (!(info.fps > 0) || !std::isfinite(info.fps)) {
    throw Error("video_unreadable", "no frame rate in the container", {.file = path.string(),
                                                                       .field = "fps"});
  }
  info.frame_count = declared;
  if (config.count_frames) {
    std::int64_t decoded = 0;
    double previous_ms = -1;
    const double expected_ms = 1000.0 / info.fps;
    while (cap.grab()) {
      const double ms = cap.get(cv::CAP_PROP_POS_MSEC);
      if (previous_ms >= 0 &&
          std::abs((ms - previous_ms) - expected_ms) > config.vfr_tolerance * expected_ms) {
        info.variable_frame_rate = true;
      }
      previous_ms = ms;
      ++decoded;
    }
    if (decoded == 0) throw Error("video_unreadable", "no frame could be decoded", site);
    if (declared > 0 && decoded < declared &&
        static_cast<double>(declared - decoded) > config.max_missing_fraction * declared) {
      throw Error("video_truncated",
                  "decoded " + std::to_string(decoded) + " of the " + std::to_string(declared) +
                      " frames the container declares (truncated or corrupt file)",
                  {.file = path.string(), .field = "frame_count"});
    }
    info.frame_count = decoded;
  }
  info.duration_s = static_cast<double>(info.frame_count) / info.fps;
  return info;
}

StageResult ProbeStage::Run(const ClipContext& context) {
  VideoInfo info;
  try {
    info = ProbeVideo(context.video.path, config_);
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.clip = context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                                 : context.clip.external_id;
    if (dynamic_cast<const PermanentError*>(&e)) throw PermanentError(e.code(), e.message(), site);
    throw Error(e.code(), e.message(), site);
  }
  StageResult result;
  result.video_info = info;
  result.measurements = {{"width", info.width},
                         {"height", info.height},
                         {"fps", info.fps},
                         {"frame_count", info.frame_count},
                         {"duration_s", info.duration_s},
                         {"variable_frame_rate", info.variable_frame_rate},
                         {"rotation_deg", info.rotation_deg},
                         {"codec", info.codec}};
  const auto& clip = context.clip;
  if (clip.end_frame && *clip.end_frame >= info.frame_count) {
    result.verdict = Verdict::kReject;
    result.reason = "span_outside_video";
    result.measurements["note"] = "end_frame " + std::to_string(*clip.end_frame) +
                                  " is past the last frame " +
                                  std::to_string(info.frame_count - 1);
  } else if (clip.end_s && *clip.end_s > info.duration_s + 1.0 / info.fps) {
    result.verdict = Verdict::kReject;
    result.reason = "span_outside_video";
  }
  return result;
}

}  // namespace doasido::video
