// An MP4 file written frame by frame through libavformat/libavcodec: H.264
// (libx264) when the encoder is there, else MPEG-4 part 2; yuv420p; a key
// frame every 2 frames so that a training loader can seek to any episode
// cheaply (LeRobot's default group of pictures).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

namespace doasido {

struct Mp4Info {
  int width = 0, height = 0;  // even
  double fps = 0;
  std::string codec;  // "h264" or "mpeg4"
  std::string pix_fmt = "yuv420p";
};

class Mp4Writer {
 public:
  // Frames are scaled to width x height (rounded down to even). Throws
  // Error("video_encode") naming the file when libav cannot set up.
  Mp4Writer(const std::filesystem::path& path, int width, int height, double fps);
  ~Mp4Writer();
  Mp4Writer(const Mp4Writer&) = delete;
  Mp4Writer& operator=(const Mp4Writer&) = delete;

  // Appends a BGR frame (CV_8UC3, any size: scaled). Throws Error("video_encode").
  void Write(const cv::Mat& bgr);
  // Flushes the encoder and writes the trailer; frames written so far.
  std::int64_t Finish();
  const Mp4Info& info() const { return info_; }

 private:
  struct Av;
  void Drain(bool flush);
  std::filesystem::path path_;
  Mp4Info info_;
  std::unique_ptr<Av> av_;
  std::int64_t frames_ = 0;
  bool finished_ = false;
};

}  // namespace doasido
