// Error codes that more than one module reads, and for each whether a retry
// can help. The worker fails a run at its first attempt when its error is
// permanent (IsPermanentError), so a deterministic failure never spends the
// attempts meant for a busy disk or a flaky network.
#pragma once

#include <string_view>

namespace doasido {

// A video file FFmpeg cannot open, or that holds fewer frames than it
// declares (video/frame_count.h), or that names a URL never downloaded.
inline constexpr const char* kVideoUnreadable = "video_unreadable";
inline constexpr const char* kVideoTruncated = "video_truncated";
inline constexpr const char* kVideoNotDownloaded = "video_not_downloaded";
// A file that is not a regular file (FIFO, device, folder, socket): it may
// never end, so it is refused without being opened.
inline constexpr const char* kNotARegularFile = "not_a_regular_file";
// A video no stage can judge: too small to show a hand, an absurd size or
// rate, no frames, audio only, a still image under a video's name.
inline constexpr const char* kUnsupportedVideo = "unsupported_video";
// A stage run went past its wall-clock limit (stages/stage_timeouts.h).
inline constexpr const char* kStageTimeout = "stage_timeout";

// True for codes a retry cannot fix: the same input gives the same error.
// Codes not listed are transient (a retry may succeed).
inline bool IsPermanentError(std::string_view code) {
  for (const std::string_view permanent :
       {std::string_view(kNotARegularFile), std::string_view(kUnsupportedVideo),
        std::string_view(kVideoUnreadable), std::string_view(kVideoTruncated),
        std::string_view(kVideoNotDownloaded), std::string_view("bad_config"),
        std::string_view("bad_embodiment"),  // a hand description that does not load
        std::string_view("bad_span")}) {
    if (code == permanent) return true;
  }
  return false;
}

}  // namespace doasido
