#include "video/probe.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

extern "C" {
#include <libavformat/avformat.h>
}

#include "core/config_check.h"
#include "core/error.h"
#include "core/error_codes.h"
#include "core/stage_progress.h"
#include "video/display_rotation.h"
#include "video/frame_count.h"

namespace doasido::video {
namespace {

// The demuxer of one file, closed when it goes out of scope.
struct Container {
  AVFormatContext* format = nullptr;
  ~Container() { avformat_close_input(&format); }
};

std::string CodecOf(const AVCodecParameters* par) {
  std::string tag;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((par->codec_tag >> (8 * i)) & 0xFF);
    if (c > ' ') tag += c;
  }
  return tag.size() == 4 ? tag : avcodec_get_name(par->codec_id);
}

// Constant-rate when every interval between consecutive presentation
// times (sorted: B-frames arrive out of order) is 1/fps within `tolerance`.
bool VariableRate(std::vector<std::int64_t> pts, double time_base, double fps, double tolerance) {
  std::sort(pts.begin(), pts.end());
  const double expected = 1.0 / fps;
  for (size_t i = 1; i < pts.size(); ++i) {
    const double interval = static_cast<double>(pts[i] - pts[i - 1]) * time_base;
    if (std::abs(interval - expected) > tolerance * expected) return true;
  }
  return false;
}

const char* FileKind(std::filesystem::file_type type) {
  switch (type) {
    case std::filesystem::file_type::fifo: return "FIFO (named pipe)";
    case std::filesystem::file_type::directory: return "folder";
    case std::filesystem::file_type::block:
    case std::filesystem::file_type::character: return "device";
    case std::filesystem::file_type::socket: return "socket";
    default: return "special file";
  }
}

// Image demuxers (png_pipe, image2, ...) open a picture as a one-frame
// stream; a picture renamed .mp4 is one of them.
bool IsStillImage(const AVFormatContext* format, const AVStream* stream) {
  const std::string name = format->iformat->name;
  const bool image_demuxer =
      name == "image2" || (name.size() > 5 && name.compare(name.size() - 5, 5, "_pipe") == 0);
  return image_demuxer || (stream->disposition & AV_DISPOSITION_ATTACHED_PIC) != 0;
}

// Limits of a video a stage can judge: a hand needs some pixels, and sizes
// or rates past any camera's are a broken header, not footage.
constexpr int kMinSide = 16;
constexpr int kMaxSide = 16384;
constexpr double kMaxFps = 1000;
constexpr std::int64_t kMinFrames = 2;

// Why no stage could judge this video ("" when one can), in words.
std::string CannotBeJudged(const VideoInfo& info) {
  const std::string size = std::to_string(info.width) + "x" + std::to_string(info.height);
  if (info.width < kMinSide || info.height < kMinSide) {
    return size + " pixels is too small to show a hand (at least " + std::to_string(kMinSide) +
           " pixels a side)";
  }
  if (info.width > kMaxSide || info.height > kMaxSide) {
    return size + " pixels is larger than any camera makes (at most " +
           std::to_string(kMaxSide) + " a side): a broken header";
  }
  if (info.fps > kMaxFps) {
    return std::to_string(info.fps) + " frames per second is past any camera's rate (at most " +
           std::to_string(static_cast<int>(kMaxFps)) + "): a broken header";
  }
  return "";
}

// Refuses a URL that was never downloaded, a missing file and anything but
// a regular file, before FFmpeg opens it.
void RequireLocalFile(const std::filesystem::path& path, const ErrorSite& site) {
  if (path.string().find("://") != std::string::npos) {
    throw Error(kVideoNotDownloaded,
                         "the video is a URL that was not downloaded (put the `download` stage "
                         "before probe in the pipeline)",
                         site);
  }
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw Error("video_missing", "no such file", site);
  if (!std::filesystem::is_regular_file(status)) {
    throw Error(kNotARegularFile,
                         std::string("a ") + FileKind(status.type()) +
                             ", not a regular file: it may never end, so it is not opened",
                         site);
  }
}

// Opens `path` into `c`; the index of its video stream, refusing audio-only
// files and still images.
int OpenVideoStream(const std::filesystem::path& path, Container& c, const ErrorSite& site) {
  if (avformat_open_input(&c.format, path.c_str(), nullptr, nullptr) < 0 ||
      avformat_find_stream_info(c.format, nullptr) < 0) {
    throw Error(kVideoUnreadable,
                         "FFmpeg cannot open it (corrupt, truncated or not a video)", site);
  }
  const int index = av_find_best_stream(c.format, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
  if (index < 0) {
    const bool audio = av_find_best_stream(c.format, AVMEDIA_TYPE_AUDIO, -1, -1, nullptr, 0) >= 0;
    if (audio) throw Error(kUnsupportedVideo, "audio only: no video stream", site);
    throw Error(kVideoUnreadable, "no video stream", site);
  }
  if (IsStillImage(c.format, c.format->streams[index])) {
    throw Error(kUnsupportedVideo,
                         std::string("a still image (") + c.format->iformat->name +
                             "), not a video, whatever its name says",
                         site);
  }
  return index;
}

// Size as displayed, rate, codec and rotation from the stream's header,
// checked to be a video a stage can judge.
VideoInfo HeaderInfo(const AVStream* stream, const std::filesystem::path& path) {
  const ErrorSite site{.file = path.string()};
  const AVCodecParameters* par = stream->codecpar;
  VideoInfo info;
  info.rotation_deg = DisplayRotation(stream);
  const bool sideways = info.rotation_deg == 90 || info.rotation_deg == 270;
  info.width = sideways ? par->height : par->width;  // as displayed, like the decoder
  info.height = sideways ? par->width : par->height;
  const AVRational rate = stream->r_frame_rate.num > 0 ? stream->r_frame_rate : stream->avg_frame_rate;
  info.fps = rate.den > 0 ? av_q2d(rate) : 0;
  info.codec = CodecOf(par);
  if (info.width <= 0 || info.height <= 0) {
    throw Error(kVideoUnreadable, "no video stream with a frame size", site);
  }
  if (!(info.fps > 0) || !std::isfinite(info.fps)) {
    throw Error(kVideoUnreadable, "no frame rate in the container",
                         {.file = path.string(), .field = "fps"});
  }
  if (const std::string why = CannotBeJudged(info); !why.empty()) {
    throw Error(kUnsupportedVideo, why, site);
  }
  return info;
}

// Counts the stream's frames (info.frame_count holds the declared count) and
// judges the rate from their presentation times; refuses a video with
// fewer than kMinFrames or more missing than the config allows.
void CountFrames(const Container& c, int index, const ProbeConfig& config,
                 const std::filesystem::path& path, VideoInfo& info) {
  const std::int64_t declared = info.frame_count;
  // Packets, not frames: every video packet of these containers is one
  // frame, and reading them costs no decoding.
  std::vector<std::int64_t> pts;
  AVPacket* packet = av_packet_alloc();
  while (av_read_frame(c.format, packet) >= 0) {
    if (packet->stream_index == index && packet->size > 0) {
      pts.push_back(packet->pts != AV_NOPTS_VALUE ? packet->pts : packet->dts);
      ReportStageProgress();
    }
    av_packet_unref(packet);
  }
  av_packet_free(&packet);
  const auto counted = static_cast<std::int64_t>(pts.size());
  if (counted < kMinFrames) {
    throw Error(kUnsupportedVideo,
                         counted == 0 ? "the video stream holds no frames"
                                      : "a single frame: no motion to judge",
                         {.file = path.string(), .field = "frame_count"});
  }
  const auto allowed = std::max(
      MissingFramesAllowed(declared),
      static_cast<std::int64_t>(std::ceil(config.max_missing_fraction * static_cast<double>(declared))));
  if (declared > 0 && counted < declared - allowed) {
    throw Error(kVideoTruncated,
                         "holds " + std::to_string(counted) + " of the " +
                             std::to_string(declared) +
                             " frames the container declares (truncated or corrupt file)",
                         {.file = path.string(), .field = "frame_count"});
  }
  info.frame_count = counted;
  const double time_base = av_q2d(c.format->streams[index]->time_base);
  info.variable_frame_rate = VariableRate(std::move(pts), time_base, info.fps, config.vfr_tolerance);
}

}  // namespace

void CheckConfig(const ProbeConfig& c, const std::string& section) {
  RequireInRange(section, "vfr_tolerance", c.vfr_tolerance, 0, 1);
  RequireInRange(section, "max_missing_fraction", c.max_missing_fraction, 0, 1);
}

VideoInfo ProbeVideo(const std::filesystem::path& path, const ProbeConfig& config) {
  const ErrorSite site{.file = path.string()};
  RequireLocalFile(path, site);
  Container c;
  const int index = OpenVideoStream(path, c, site);
  const AVStream* stream = c.format->streams[index];
  VideoInfo info = HeaderInfo(stream, path);
  info.frame_count = stream->nb_frames;
  if (config.count_frames) CountFrames(c, index, config, path, info);
  info.duration_s = static_cast<double>(info.frame_count) / info.fps;
  return info;
}

}  // namespace doasido::video
