// The `probe` queue stage, the first: probes the clip's video
// (video/probe.h ProbeVideo) and checks that the clip's span lies inside
// it. Measurements: the video's width, height, fps, frame_count,
// duration_s, variable_frame_rate, rotation_deg and codec.
#pragma once

#include <string>

#include "core/config.h"
#include "stages/stage.h"
#include "video/probe.h"

namespace doasido::stages {

// The stage's name: its queue name, config section and artifact folder.
inline constexpr const char* kProbeStageName = "probe";
// Reason code: the clip's end frame or end time lies past the video's end.
inline constexpr const char* kReasonSpanOutsideVideo = "span_outside_video";

// The first queue stage: probes the clip's video and checks that the clip's
// span lies inside it.
class ProbeStage : public Stage {
 public:
  explicit ProbeStage(video::ProbeConfig config = {}) : config_(config) {}
  std::string Name() const override { return kProbeStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;

 private:
  video::ProbeConfig config_;
};

}  // namespace doasido::stages
