// Probing a video from its container (libavformat), without decoding: size,
// frame rate, frame count (the video packets), duration, variable frame rate
// (from the packets' presentation times), display rotation and codec. The
// `probe` queue stage that runs it on each clip is stages/probe_stage.h.
#pragma once

#include <filesystem>

#include "core/config.h"
#include "core/records.h"

namespace doasido::video {

struct ProbeConfig {
  // Read every video packet to count the frames (exact, catches truncated
  // files, gives the frame intervals) rather than trusting the container's
  // declared count. No frame is decoded either way.
  bool count_frames = true;
  // A video is variable-frame-rate when an interval between consecutive
  // presentation times differs from 1/fps by more than this fraction.
  double vfr_tolerance = 0.25;
  // With count_frames, fail when the file holds fewer frames than the
  // container declares by more than this fraction, or by more than the
  // shared allowance of video/frame_count.h, whichever is larger.
  double max_missing_fraction = 0.02;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ProbeConfig, count_frames, vfr_tolerance,
                                                max_missing_fraction)
// Tolerances are fractions in [0, 1]; throws Error("bad_config").
void CheckConfig(const ProbeConfig& c, const std::string& section);

// Throws Error naming the file: "video_missing" (may appear later: retried),
// and these codes a retry cannot change (permanent, core/error_codes.h):
// kNotARegularFile (a FIFO, device or folder: refused without opening it),
// kVideoUnreadable (FFmpeg cannot open it), kUnsupportedVideo (no stage
// could judge it: under 16 or over 16384 pixels a side, over 1000 fps,
// fewer than 2 frames, audio only, a still image), kVideoTruncated (holds
// fewer frames than declared, beyond the allowance).
VideoInfo ProbeVideo(const std::filesystem::path& path, const ProbeConfig& config = {});

}  // namespace doasido::video
