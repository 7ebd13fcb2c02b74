// One sequential decode pass over a span of a video file, delivering every
// frame at a reduced analysis resolution.
//
// The analysis size follows PySceneDetect's automatic downscale so that shot
// scores computed on these frames equal its published ones: the factor is
// max(width, height) / analysis_size (no scaling when the longer side is
// already smaller), the target size is each side divided by the factor and
// rounded half-to-even (Python's round), and the resize is bilinear
// (cv::INTER_LINEAR). The full-resolution size is kept in the geometry so
// that boxes found at analysis resolution can be mapped back (and boxes given
// at full resolution mapped in).
//
// Decoding is libavcodec, single-threaded (a worker process per core scales
// better than threads inside one decode), and by default skips H.264/HEVC's
// in-loop deblocking filter: about a fifth of the decode time, and at
// analysis size the difference is a few grey levels on block edges (every
// PySceneDetect golden still matches: tests/filters_shot_boundary_test.cc).
// Frames are converted from the decoder's YUV straight to BGR at analysis
// size by libswscale (bilinear), so no full-resolution BGR image is ever
// made; `exact_scaling` instead gives the pixels of converting at full size
// and resizing with cv::resize as PySceneDetect does, converting only the
// pixels that resize weighs where that is much less than the frame
// (video/weighed_pixels.h).
//
// Frames before the span are decoded but not converted; a span that starts
// more than `seek_after_frames` into the file seeks to the key frame before
// it first (frame indices then come from timestamps, which needs a constant
// frame rate; a stream without one is decoded from the start). A decode
// that ends before the number of frames the container declares, or before
// the requested span ends, by more than the shared allowance of
// video/frame_count.h, is a truncated or corrupt file: Next() throws
// Error(kVideoTruncated) (permanent) naming the file and the first frame it
// could not decode. A span that runs into an allowed short tail just ends
// early (delivered() tells how many frames came).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

namespace doasido {

struct DecoderOptions {
  // Target length of the longer side at analysis resolution (PySceneDetect's
  // DEFAULT_MIN_WIDTH). 0 keeps full resolution.
  int analysis_size = 256;
  // Span to deliver, as 0-based frame indices of the file; last_frame < 0
  // means "to the end of the file". Inclusive.
  std::int64_t first_frame = 0;
  std::int64_t last_frame = -1;
  // The same span in seconds, used only when the frame bound is unset
  // (first_frame == 0 / last_frame < 0) and the value is >= 0; converted
  // with the stream's frame rate (nearest frame).
  double first_s = -1;
  double last_s = -1;
  // How many frames short of the container's declared count the decode may
  // end without being called truncated, beyond the shared rule of
  // video/frame_count.h (which always applies).
  std::int64_t frame_count_tolerance = 0;
  // Clip label used in error messages (may be empty).
  std::string clip;
  // Skip the in-loop deblocking filter (H.264, HEVC): faster, slightly
  // blockier frames that are never used as anything but analysis input.
  bool skip_loop_filter = true;
  // Convert at full resolution and resize with cv::resize (PySceneDetect's
  // exact pixel path) instead of scaling in libswscale.
  bool exact_scaling = false;
  // Seek when the span starts this many frames or more into the file.
  std::int64_t seek_after_frames = 300;
};

// Sizes are in display orientation: a file whose display matrix turns it by
// 90 or 270 degrees has its frames delivered turned, as players show them.
struct VideoGeometry {
  int full_width = 0, full_height = 0;  // decoded frame size
  int width = 0, height = 0;            // analysis size
  double downscale = 1.0;               // full / analysis (PySceneDetect's factor)
  double fps = 0;
  std::int64_t declared_frames = 0;  // container's frame count (0 if unknown)
};

struct AnalysisFrame {
  std::int64_t index = 0;  // 0-based frame index in the file
  double timestamp_s = 0;  // presentation time of the frame
  cv::Mat bgr;             // CV_8UC3 at analysis size; valid until the next Next()
};

// PySceneDetect's downscale factor for a frame of `width` x `height` and a
// target longer side `analysis_size` (>= 1 means shrink by that factor).
double AnalysisDownscale(int width, int height, int analysis_size);
// The analysis frame size for that factor (rounded half-to-even, >= 1).
cv::Size AnalysisSize(int width, int height, int analysis_size);

class VideoDecoder {
 public:
  // Opens `path` and positions at options.first_frame. Throws
  // Error("video_open_failed") when the file is missing or not a video, and
  // Error("video_truncated") when the span starts past the decodable end.
  VideoDecoder(const std::filesystem::path& path, const DecoderOptions& options);
  ~VideoDecoder();
  VideoDecoder(const VideoDecoder&) = delete;
  VideoDecoder& operator=(const VideoDecoder&) = delete;

  const VideoGeometry& geometry() const { return geometry_; }
  const std::filesystem::path& path() const { return path_; }

  // Decodes the next frame of the span into `frame`. Returns false once the
  // span (or the file) has ended normally; throws Error("video_truncated")
  // when decoding stops early (see the file comment).
  bool Next(AnalysisFrame* frame);

  // The span's first frame (after converting first_s, if that was used).
  std::int64_t first_frame() const { return options_.first_frame; }
  // Frames delivered so far.
  std::int64_t delivered() const { return delivered_; }
  // True once the exact path converts only the pixels cv::resize weighs:
  // after the first frame, where that was worth it and gave the full
  // conversion's bytes (video/weighed_pixels.h).
  bool converts_weighed_pixels() const;

 private:
  struct Codec;  // libav state (video/video_decoder.cc)

  [[noreturn]] void ThrowTruncated(std::int64_t frame, const std::string& why) const;
  // Frames the decode may end short of the declared count (video/frame_count.h).
  std::int64_t Tolerance() const;
  // Decodes the next frame of the file into the codec's frame; false at the
  // end of the stream.
  bool DecodeNext();
  // Index of the decoded frame: counted, or from its timestamp after a seek.
  std::int64_t DecodedIndex() const;
  void SeekBefore(std::int64_t frame);
  // The decoded frame at analysis size in display orientation.
  void Convert(cv::Mat* bgr);
  // The same in the coded (unrotated) orientation.
  void ConvertCoded(cv::Mat* bgr);
  // The whole decoded frame as BGR of `width` x `height` (libswscale).
  void SwsConvert(int width, int height, cv::Mat* bgr);
  // The exact path's full-size BGR (full_) at the pixels cv::resize weighs
  // for `target` (video/weighed_pixels.h); false when the whole frame must
  // be converted instead.
  bool ConvertWeighed(cv::Size target);

  std::filesystem::path path_;
  DecoderOptions options_;
  VideoGeometry geometry_;
  std::unique_ptr<Codec> codec_;
  cv::Mat full_;
  cv::Mat padded_;    // a conversion at a width rounded up to 16 (SwsConvert)
  cv::Mat coded_;     // a rotated file's frame before turning
  int rotation_ = 0;  // video/display_rotation.h
  std::int64_t next_index_ = 0;  // index of the next decoded frame
  std::int64_t delivered_ = 0;
  bool index_from_pts_ = false;
  bool pending_ = false;  // a decoded frame waits to be delivered
  bool done_ = false;
};

}  // namespace doasido
