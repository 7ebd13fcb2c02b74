// Point following when a bundle has no point tracks: OpenCV's pyramidal
// Lucas-Kanade between consecutive frames of the clip's video, kept only
// where tracking back lands within `max_fb_error_px` of the start (the
// forward-backward check), the classical fallback the adaptive guidance
// (recon/track/adaptive_guidance.h) reports as "lucas_kanade".
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include <opencv2/core.hpp>

#include "recon/track/adaptive_guidance.h"

namespace doasido::recon {

struct LucasKanadeOptions {
  int window_px = 21;
  int pyramid_levels = 3;
  double max_fb_error_px = 1.0;
};

// `gray` holds the clip's frames (CV_8U), frame k at index k.
PointFollower FollowWithLucasKanade(std::vector<cv::Mat> gray, const LucasKanadeOptions& options = {});

// Frames [first, first + count) of `video` through OpenCV's FFmpeg reader,
// gray, resized to width x height. Throws Error("video_unreadable") naming
// the file when it cannot be opened or ends early.
std::vector<cv::Mat> ReadGrayFrames(const std::filesystem::path& video, std::int64_t first,
                                    int count, int width, int height);

}  // namespace doasido::recon
