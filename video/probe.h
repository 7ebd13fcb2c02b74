// Probing a video: size, frame rate, frame count, duration, rotation and
// codec through OpenCV's FFmpeg backend.
#pragma once

#include <filesystem>

#include "core/config.h"
#include "db/records.h"
#include "db/stage.h"

namespace doasido::video {

inline constexpr const char* kProbeStageName = "probe";

struct ProbeConfig {
  // Decode every frame to count them (exact, and catches truncated files)
  // rather than trusting the container's declared count.
  bool count_frames = true;
  // A video is variable-frame-rate when a frame interval differs from 1/fps
  // by more than this fraction.
  double vfr_tolerance = 0.25;
  // With count_frames, fail when fewer frames decode than the container
  // declares by more than this fraction (a truncated or corrupt file).
  double max_missing_fraction = 0.02;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ProbeConfig, count_frames, vfr_tolerance,
                                                max_missing_fraction)
// Tolerances are fractions in [0, 1]; throws Error("bad_config").
void CheckConfig(const ProbeConfig& c, const std::string& section);

// Throws Error naming the file: "video_missing", "video_unreadable" (cannot
// be opened or has no frames), "video_truncated" (decodes fewer frames than
// declared).
VideoInfo ProbeVideo(const std::filesystem::path& path, const ProbeConfig& config = {});

// The first queue stage: probes the clip's video and checks that the clip's
// span lies inside it.
class ProbeStage : public Stage {
 public:
  explicit ProbeStage(ProbeConfig config = {}) : config_(config) {}
  std::string Name() const override { return kProbeStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;

 private:
  ProbeConfig config_;
};

}  // namespace doasido::video
