#include "video/mp4_writer.h"

#include <opencv2/imgproc.hpp>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

#include "core/error.h"

namespace doasido {

struct Mp4Writer::Av {
  AVFormatContext* format = nullptr;
  AVCodecContext* codec = nullptr;
  AVStream* stream = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  SwsContext* sws = nullptr;

  ~Av() {
    sws_freeContext(sws);
    av_packet_free(&packet);
    av_frame_free(&frame);
    avcodec_free_context(&codec);
    if (format) {
      if (format->pb) avio_closep(&format->pb);
      avformat_free_context(format);
    }
  }
};

namespace {

void Check(int rc, const char* what, const std::filesystem::path& path) {
  if (rc >= 0) return;
  char text[AV_ERROR_MAX_STRING_SIZE] = {0};
  av_strerror(rc, text, sizeof text);
  throw Error("video_encode", std::string(what) + ": " + text, {.file = path.string()});
}

}  // namespace

Mp4Writer::Mp4Writer(const std::filesystem::path& path, int width, int height, double fps)
    : path_(path), av_(std::make_unique<Av>()) {
  info_.width = std::max(2, width & ~1);
  info_.height = std::max(2, height & ~1);
  info_.fps = fps;
  Check(avformat_alloc_output_context2(&av_->format, nullptr, "mp4", path.c_str()),
        "cannot start an MP4 file", path);
  const AVCodec* codec = avcodec_find_encoder_by_name("libx264");
  if (!codec) codec = avcodec_find_encoder(AV_CODEC_ID_MPEG4);
  if (!codec) throw Error("video_encode", "libavcodec has neither H.264 nor MPEG-4", {.file = path.string()});
  info_.codec = codec->id == AV_CODEC_ID_H264 ? "h264" : "mpeg4";
  av_->stream = avformat_new_stream(av_->format, nullptr);
  av_->codec = avcodec_alloc_context3(codec);
  if (!av_->stream || !av_->codec) throw Error("video_encode", "out of memory", {.file = path.string()});
  AVCodecContext* c = av_->codec;
  c->width = info_.width;
  c->height = info_.height;
  c->pix_fmt = AV_PIX_FMT_YUV420P;
  c->framerate = av_d2q(fps, 100000);
  c->time_base = av_inv_q(c->framerate);
  c->gop_size = 2;
  c->max_b_frames = 0;
  if (info_.codec == "h264") {
    av_opt_set(c->priv_data, "preset", "veryfast", 0);
    av_opt_set(c->priv_data, "crf", "23", 0);
  } else {
    c->bit_rate = 4'000'000;
  }
  if (av_->format->oformat->flags & AVFMT_GLOBALHEADER) c->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  Check(avcodec_open2(c, codec, nullptr), "cannot open the encoder", path);
  Check(avcodec_parameters_from_context(av_->stream->codecpar, c), "codec parameters", path);
  av_->stream->time_base = c->time_base;
  av_->stream->avg_frame_rate = c->framerate;
  Check(avio_open(&av_->format->pb, path.c_str(), AVIO_FLAG_WRITE), "cannot create the file", path);
  Check(avformat_write_header(av_->format, nullptr), "cannot write the header", path);
  av_->frame = av_frame_alloc();
  av_->packet = av_packet_alloc();
  av_->frame->format = c->pix_fmt;
  av_->frame->width = c->width;
  av_->frame->height = c->height;
  Check(av_frame_get_buffer(av_->frame, 0), "frame buffer", path);
  av_->sws = sws_getContext(c->width, c->height, AV_PIX_FMT_BGR24, c->width, c->height,
                            AV_PIX_FMT_YUV420P, SWS_BILINEAR, nullptr, nullptr, nullptr);
}

Mp4Writer::~Mp4Writer() = default;

void Mp4Writer::Write(const cv::Mat& bgr) {
  cv::Mat sized = bgr;
  if (bgr.cols != info_.width || bgr.rows != info_.height) {
    cv::resize(bgr, sized, cv::Size(info_.width, info_.height), 0, 0, cv::INTER_AREA);
  }
  if (!sized.isContinuous()) sized = sized.clone();
  Check(av_frame_make_writable(av_->frame), "frame buffer", path_);
  const uint8_t* src[1] = {sized.data};
  const int stride[1] = {static_cast<int>(sized.step[0])};
  sws_scale(av_->sws, src, stride, 0, info_.height, av_->frame->data, av_->frame->linesize);
  av_->frame->pts = frames_++;
  Check(avcodec_send_frame(av_->codec, av_->frame), "cannot encode a frame", path_);
  Drain(false);
}

void Mp4Writer::Drain(bool flush) {
  for (;;) {
    const int rc = avcodec_receive_packet(av_->codec, av_->packet);
    if (rc == AVERROR(EAGAIN) || (flush && rc == AVERROR_EOF)) return;
    Check(rc, "cannot encode a frame", path_);
    av_packet_rescale_ts(av_->packet, av_->codec->time_base, av_->stream->time_base);
    av_->packet->stream_index = av_->stream->index;
    Check(av_interleaved_write_frame(av_->format, av_->packet), "cannot write a frame", path_);
  }
}

std::int64_t Mp4Writer::Finish() {
  if (finished_) return frames_;
  finished_ = true;
  Check(avcodec_send_frame(av_->codec, nullptr), "cannot flush the encoder", path_);
  Drain(true);
  Check(av_write_trailer(av_->format), "cannot write the trailer", path_);
  // Closing writes what the I/O buffer still holds: a full disk shows here.
  if (av_->format->pb) Check(avio_closep(&av_->format->pb), "cannot close the file", path_);
  return frames_;
}

}  // namespace doasido
