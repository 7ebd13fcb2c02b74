#include "video/video_decoder.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/stage_progress.h"
#include "video/display_rotation.h"
#include "video/frame_count.h"
#include "video/sws_buffer.h"
#include "video/weighed_pixels.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libswscale/swscale.h>
}

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

struct VideoDecoder::Codec {
  AVFormatContext* format = nullptr;
  AVCodecContext* context = nullptr;
  AVPacket* packet = nullptr;
  AVFrame* frame = nullptr;
  SwsContext* sws = nullptr;
  // The exact path's conversion of the weighed pixels only, once the
  // clip's first frame showed it equal to the full conversion.
  std::unique_ptr<WeighedPixels> weighed;
  bool weighed_checked = false;
  bool weighed_off = false;
  int stream = -1;
  double time_base = 0;     // seconds per pts unit
  std::int64_t start_pts = 0;
  bool flushed = false;     // the end-of-stream packet was sent

  ~Codec() {
    sws_freeContext(sws);
    av_frame_free(&frame);
    av_packet_free(&packet);
    avcodec_free_context(&context);
    avformat_close_input(&format);
  }
};

namespace {

double Rational(AVRational r) { return r.den != 0 ? av_q2d(r) : 0.0; }

// The steps of VideoDecoder's constructor.

// Opens `path`, finds its best video stream and opens a one-thread decoder
// for it, or throws Error("video_open_failed") naming `site`.
void OpenDecoder(const std::filesystem::path& path, bool skip_loop_filter, const ErrorSite& site,
                 AVFormatContext*& format, AVCodecContext*& context, int& stream) {
  if (avformat_open_input(&format, path.c_str(), nullptr, nullptr) < 0 ||
      avformat_find_stream_info(format, nullptr) < 0) {
    throw Error("video_open_failed",
                "FFmpeg could not open the file as a video (not a video, or truncated before "
                "its index)",
                site);
  }
  const AVCodec* decoder = nullptr;
  stream = av_find_best_stream(format, AVMEDIA_TYPE_VIDEO, -1, -1, &decoder, 0);
  if (stream < 0 || decoder == nullptr) {
    throw Error("video_open_failed", "the file has no video stream FFmpeg can decode", site);
  }
  context = avcodec_alloc_context3(decoder);
  if (context == nullptr ||
      avcodec_parameters_to_context(context, format->streams[stream]->codecpar) < 0) {
    throw Error("video_open_failed", "cannot set up the video decoder", site);
  }
  context->thread_count = 1;
  if (skip_loop_filter) context->skip_loop_filter = AVDISCARD_ALL;
  if (avcodec_open2(context, decoder, nullptr) < 0) {
    throw Error("video_open_failed", "cannot open the video decoder", site);
  }
}

// The stream's geometry in display orientation (what players show; the
// coded frames are turned in Convert), its rate, its declared frame count
// and the analysis size.
VideoGeometry StreamGeometry(const AVFormatContext& format, const AVStream& stream,
                             const AVCodecContext& context, int rotation, int analysis_size,
                             const ErrorSite& site) {
  VideoGeometry g;
  const bool sideways = rotation == 90 || rotation == 270;
  g.full_width = sideways ? context.height : context.width;
  g.full_height = sideways ? context.width : context.height;
  g.fps = Rational(stream.avg_frame_rate);
  if (g.fps <= 0) g.fps = Rational(stream.r_frame_rate);
  g.declared_frames = stream.nb_frames;
  if (g.declared_frames <= 0 && g.fps > 0) {
    // As OpenCV's FFmpeg backend counts a stream without a frame count.
    double duration_s = stream.duration != AV_NOPTS_VALUE
                            ? static_cast<double>(stream.duration) * Rational(stream.time_base)
                            : static_cast<double>(format.duration) / AV_TIME_BASE;
    g.declared_frames =
        duration_s > 0 ? static_cast<std::int64_t>(std::floor(duration_s * g.fps + 0.5)) : 0;
  }
  if (g.full_width <= 0 || g.full_height <= 0) {
    throw Error("video_open_failed", "the video stream has no frame size", site);
  }
  const cv::Size size = AnalysisSize(g.full_width, g.full_height, analysis_size);
  g.width = size.width;
  g.height = size.height;
  g.downscale = AnalysisDownscale(g.full_width, g.full_height, analysis_size);
  return g;
}

// A span given in seconds as frames at `fps`.
void ResolveSpan(double fps, DecoderOptions& options) {
  if (!(fps > 0)) return;
  if (options.first_frame == 0 && options.first_s > 0) {
    options.first_frame = std::llround(options.first_s * fps);
  }
  if (options.last_frame < 0 && options.last_s >= 0) {
    options.last_frame = std::llround(options.last_s * fps);
  }
}

}  // namespace

VideoDecoder::VideoDecoder(const std::filesystem::path& path, const DecoderOptions& options)
    : path_(path), options_(options), codec_(std::make_unique<Codec>()) {
  const ErrorSite site{.clip = options.clip, .file = path.string()};
  if (!std::filesystem::exists(path)) {
    throw Error("video_open_failed", "video file does not exist", site);
  }
  av_log_set_level(AV_LOG_FATAL);  // our own errors name the clip and file
  Codec& c = *codec_;
  OpenDecoder(path, options.skip_loop_filter, site, c.format, c.context, c.stream);
  AVStream* stream = c.format->streams[c.stream];
  c.packet = av_packet_alloc();
  c.frame = av_frame_alloc();
  c.time_base = Rational(stream->time_base);
  c.start_pts = stream->start_time != AV_NOPTS_VALUE ? stream->start_time : 0;
  rotation_ = DisplayRotation(stream);
  geometry_ = StreamGeometry(*c.format, *stream, *c.context, rotation_, options.analysis_size, site);
  ResolveSpan(geometry_.fps, options_);
  if (options_.first_frame < 0) {
    throw Error("bad_span", "first frame is negative",
                {.clip = options.clip, .file = path.string(), .field = "start_frame"});
  }
  const bool constant_rate =
      av_cmp_q(stream->avg_frame_rate, stream->r_frame_rate) == 0 && geometry_.fps > 0;
  if (options_.first_frame >= options_.seek_after_frames && options_.seek_after_frames > 0 &&
      constant_rate) {
    SeekBefore(options_.first_frame);
  }
  // Decode without converting up to the span.
  bool rewound = false;
  while (next_index_ < options_.first_frame) {
    if (!DecodeNext()) {
      if (geometry_.declared_frames > 0 &&
          next_index_ < geometry_.declared_frames - Tolerance()) {
        ThrowTruncated(next_index_, "decoding stopped before the clip's first frame");
      }
      done_ = true;
      break;
    }
    if (index_from_pts_ && DecodedIndex() > options_.first_frame && !rewound) {
      // The seek overshot (no key frame where the index said): start over.
      rewound = true;
      av_seek_frame(codec_->format, codec_->stream, codec_->start_pts, AVSEEK_FLAG_BACKWARD);
      avcodec_flush_buffers(codec_->context);
      continue;
    }
    if (DecodedIndex() >= options_.first_frame) {
      pending_ = true;  // the seek landed on the first frame: deliver it
      break;
    }
    next_index_ = DecodedIndex() + 1;
  }
}

VideoDecoder::~VideoDecoder() = default;

void VideoDecoder::SeekBefore(std::int64_t frame) {
  Codec& c = *codec_;
  const double seconds = static_cast<double>(frame) / geometry_.fps;
  const auto target = c.start_pts + static_cast<std::int64_t>(std::floor(seconds / c.time_base));
  if (av_seek_frame(c.format, c.stream, target, AVSEEK_FLAG_BACKWARD) < 0) return;
  avcodec_flush_buffers(c.context);
  index_from_pts_ = true;
  // The frame index is unknown until the first frame after the seek arrives.
  next_index_ = -1;
}

std::int64_t VideoDecoder::DecodedIndex() const {
  if (!index_from_pts_) return next_index_;
  const AVFrame* f = codec_->frame;
  const std::int64_t pts =
      f->best_effort_timestamp != AV_NOPTS_VALUE ? f->best_effort_timestamp : f->pts;
  return std::llround(static_cast<double>(pts - codec_->start_pts) * codec_->time_base *
                      geometry_.fps);
}

bool VideoDecoder::DecodeNext() {
  Codec& c = *codec_;
  while (true) {
    const int received = avcodec_receive_frame(c.context, c.frame);
    if (received == 0) {
      ReportStageProgress();
      return true;
    }
    if (received != AVERROR(EAGAIN) || c.flushed) return false;
    // Feed packets until the decoder takes one (corrupt packets are skipped:
    // the frame count then tells a damaged file from a complete one).
    while (true) {
      if (av_read_frame(c.format, c.packet) < 0) {
        avcodec_send_packet(c.context, nullptr);
        c.flushed = true;
        break;
      }
      const bool ours = c.packet->stream_index == c.stream;
      const int sent = ours ? avcodec_send_packet(c.context, c.packet) : -1;
      av_packet_unref(c.packet);
      if (ours && sent >= 0) break;
    }
  }
}

void VideoDecoder::Convert(cv::Mat* out) {
  if (rotation_ != 90 && rotation_ != 180 && rotation_ != 270) {
    ConvertCoded(out);
    return;
  }
  ConvertCoded(&coded_);
  cv::rotate(coded_, *out,
             rotation_ == 90    ? cv::ROTATE_90_COUNTERCLOCKWISE
             : rotation_ == 180 ? cv::ROTATE_180
                                : cv::ROTATE_90_CLOCKWISE);
}

namespace {

// libswscale's flags for every conversion here (OpenCV's FFmpeg reader
// converts at the same size, where the scaler's filter does not matter).
constexpr int kSwsFlags = SWS_BILINEAR;

}  // namespace

void VideoDecoder::SwsConvert(int width, int height, cv::Mat* bgr) {
  Codec& c = *codec_;
  const AVFrame* f = c.frame;
  // libswscale's vector converter at the frame's own size writes whole
  // blocks of 8 pixels and leaves a row's last width % 8 pixels as they
  // were (bass_guitar.mp4, 470 wide: its last 6 columns were whatever the
  // buffer held, so a clip's pixels depended on what the worker decoded
  // before). It converts a width rounded up to 16 instead, reading the
  // decoder's padding (decoded macroblocks or the plane's alignment), and
  // the frame is a copy of the first `width` columns of that.
  const bool same_size = width == f->width && height == f->height;
  const int padded = (width + 15) / 16 * 16;
  const bool pad = same_size && padded != width && f->linesize[0] >= padded &&
                   (f->format != AV_PIX_FMT_YUV420P ||
                    (f->linesize[1] >= padded / 2 && f->linesize[2] >= padded / 2));
  const int sws_width = pad ? padded : width;
  c.sws = sws_getCachedContext(c.sws, pad ? padded : f->width, f->height,
                               static_cast<AVPixelFormat>(f->format), sws_width, height,
                               AV_PIX_FMT_BGR24, kSwsFlags, nullptr, nullptr, nullptr);
  if (c.sws == nullptr) {
    throw Error("corrupt_video", "cannot convert the decoded pixel format",
                {.clip = options_.clip, .file = path_.string()});
  }
  cv::Mat& target = pad ? padded_ : *bgr;
  EnsureSwsOutput(&target, height, sws_width);
  uint8_t* planes[1] = {target.data};
  const int strides[1] = {static_cast<int>(target.step[0])};
  sws_scale(c.sws, f->data, f->linesize, 0, f->height, planes, strides);
  if (pad) {
    EnsureSwsOutput(bgr, height, width);  // the same room as a direct conversion
    padded_.colRange(0, width).copyTo(*bgr);
  }
}

bool VideoDecoder::ConvertWeighed(cv::Size target) {
  Codec& c = *codec_;
  const AVFrame* f = c.frame;
  if (c.weighed_off || f->format != AV_PIX_FMT_YUV420P) return false;
  const cv::Size full(f->width, f->height);
  if (!c.weighed) {
    c.weighed = std::make_unique<WeighedPixels>(full, target, kSwsFlags);
    // Its small frame has 4 pixels per weighed one: worth it where that is
    // well under the whole frame (the larger shrinks: 720p and up to 256).
    c.weighed_off = 4 * c.weighed->fraction() > 0.5;
    if (c.weighed_off) return false;
  }
  EnsureSwsOutput(&full_, full.height, full.width);
  const uint8_t* const planes[3] = {f->data[0], f->data[1], f->data[2]};
  const int strides[3] = {f->linesize[0], f->linesize[1], f->linesize[2]};
  if (!c.weighed->Convert(planes, strides, &full_)) {
    c.weighed_off = true;
    return false;
  }
  if (!c.weighed_checked) {
    // The first frame, both ways: the full conversion stays for the clip
    // unless the two agree to the byte.
    cv::Mat weighed, reference;
    cv::resize(full_, weighed, target, 0, 0, cv::INTER_LINEAR);
    SwsConvert(full.width, full.height, &full_);
    cv::resize(full_, reference, target, 0, 0, cv::INTER_LINEAR);
    c.weighed_checked = true;
    c.weighed_off = cv::norm(weighed, reference, cv::NORM_INF) != 0;
  }
  return true;
}

bool VideoDecoder::converts_weighed_pixels() const {
  return codec_->weighed_checked && !codec_->weighed_off;
}

void VideoDecoder::ConvertCoded(cv::Mat* bgr) {
  const AVFrame* f = codec_->frame;
  const bool sideways = rotation_ == 90 || rotation_ == 270;
  const int width = sideways ? geometry_.height : geometry_.width;  // analysis size, coded
  const int height = sideways ? geometry_.width : geometry_.height;
  if (!options_.exact_scaling) {
    SwsConvert(width, height, bgr);
    return;
  }
  if (f->width == width && f->height == height) {
    SwsConvert(width, height, &full_);
    *bgr = full_;
    return;
  }
  if (!ConvertWeighed(cv::Size(width, height))) SwsConvert(f->width, f->height, &full_);
  cv::resize(full_, *bgr, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);
}

std::int64_t VideoDecoder::Tolerance() const {
  return std::max(options_.frame_count_tolerance, MissingFramesAllowed(geometry_.declared_frames));
}

void VideoDecoder::ThrowTruncated(std::int64_t frame, const std::string& why) const {
  std::string message = why + " (could not decode frame " + std::to_string(frame);
  if (geometry_.declared_frames > 0) {
    message += " of " + std::to_string(geometry_.declared_frames) + " declared";
  }
  message += "); the file is truncated or corrupt";
  throw Error(
      kVideoTruncated, message,
      {.clip = options_.clip, .file = path_.string(), .field = "frame " + std::to_string(frame)});
}

bool VideoDecoder::Next(AnalysisFrame* frame) {
  if (done_) return false;
  if (options_.last_frame >= 0 && next_index_ > options_.last_frame) {
    done_ = true;
    return false;
  }
  if (!pending_ && !DecodeNext()) {
    done_ = true;
    if (geometry_.declared_frames > 0 &&
        next_index_ < geometry_.declared_frames - Tolerance()) {
      ThrowTruncated(next_index_, "decoding stopped early");
    }
    if (geometry_.declared_frames == 0 && delivered_ == 0) {
      ThrowTruncated(next_index_, "no frame could be decoded");
    }
    return false;
  }
  pending_ = false;
  const AVFrame* f = codec_->frame;
  const std::int64_t index = DecodedIndex();
  if (options_.last_frame >= 0 && index > options_.last_frame) {
    done_ = true;
    return false;
  }
  const bool sideways = rotation_ == 90 || rotation_ == 270;
  const int coded_w = sideways ? geometry_.full_height : geometry_.full_width;
  const int coded_h = sideways ? geometry_.full_width : geometry_.full_height;
  if (f->width != coded_w || f->height != coded_h) {
    throw Error("corrupt_video",
                "frame " + std::to_string(index) + " is " + std::to_string(f->width) + "x" +
                    std::to_string(f->height) + ", the stream declares " +
                    std::to_string(coded_w) + "x" + std::to_string(coded_h),
                {.clip = options_.clip,
                 .file = path_.string(),
                 .field = "frame " + std::to_string(index)});
  }
  frame->index = index;
  const std::int64_t pts =
      f->best_effort_timestamp != AV_NOPTS_VALUE ? f->best_effort_timestamp : f->pts;
  frame->timestamp_s = pts != AV_NOPTS_VALUE
                           ? static_cast<double>(pts - codec_->start_pts) * codec_->time_base
                           : (geometry_.fps > 0 ? static_cast<double>(index) / geometry_.fps : 0);
  Convert(&frame->bgr);
  next_index_ = index + 1;
  ++delivered_;
  return true;
}

}  // namespace doasido
