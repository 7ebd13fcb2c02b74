// PySceneDetect's analysis pixels without converting a whole frame.
//
// The exact decode converts a frame to BGR at full size with libswscale (as
// OpenCV's FFmpeg reader does) and shrinks it with cv::resize INTER_LINEAR.
// That shrink weighs at most two source columns per output column and two
// rows per output row, and a source byte whose weight is zero adds nothing
// to the sum. At 1280x720 -> 256x144 the weighed pixels are one in 25; at
// 1920x1080 -> 256x144 about one in 14. WeighedPixels converts only those:
// each one's Y, U and V go into a 2x2 block of a small 4:2:0 frame (so the
// block has that pixel's own chroma), libswscale converts the small frame
// with the converter it uses for the full one, and each block's BGR is
// written back at its pixel in the full-size BGR buffer. cv::resize then
// reads that buffer as before; the pixels it skips or weighs by zero hold
// whatever they held.
//
// The arithmetic is libswscale's and OpenCV's own, so the result is the
// full conversion's byte for byte when libswscale picks the same per-pixel
// converter for both sizes. The decoder checks that on a clip's first frame
// against the full conversion and keeps the full conversion for the clip
// when they differ (video/video_decoder.cc).
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

struct SwsContext;

namespace doasido {

// The source columns (or rows) that cv::resize INTER_LINEAR weighs when it
// shrinks `source` pixels to `target`, ascending: each output's left (top)
// tap, and its right (bottom) tap unless that tap's fraction is exactly 0.
std::vector<int> WeighedTaps(int source, int target);

class WeighedPixels {
 public:
  // For YUV 4:2:0 frames of `full` size shrunk to `target`, converted with
  // libswscale's `sws_flags` (those of the full conversion).
  WeighedPixels(cv::Size full, cv::Size target, int sws_flags);
  ~WeighedPixels();
  WeighedPixels(const WeighedPixels&) = delete;
  WeighedPixels& operator=(const WeighedPixels&) = delete;

  // Writes the BGR of every weighed pixel of the frame `planes` / `strides`
  // (Y, U, V) into `full_bgr` (CV_8UC3 of the full size, allocated by the
  // caller); other pixels are left as they are. False when libswscale cannot
  // convert the small frame.
  bool Convert(const std::uint8_t* const planes[3], const int strides[3], cv::Mat* full_bgr);

  // Weighed pixels over all pixels of the frame.
  double fraction() const;

 private:
  cv::Size full_;
  std::vector<int> columns_, rows_;
  int small_width_ = 0;  // the small frame's width: 2 per column, padded
  std::vector<std::uint16_t> y_;  // two equal Y bytes per weighed pixel and row
  std::vector<std::uint8_t> u_, v_;
  cv::Mat small_bgr_;
  int sws_flags_ = 0;
  SwsContext* sws_ = nullptr;  // made on the first Convert
};

}  // namespace doasido
