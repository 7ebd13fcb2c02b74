// Stage "hand_object_detector": runs the external hand-object detector
// command (filters::RunExternalDetector, filters/interaction.h, where its
// contract is) on the clip and returns its boxes as StageResult::detections
// (source "detector:external") with a per-frame count in the measurements.
// Runs before the analysis stage so that the analysis pass sees the boxes;
// with no command configured it passes, reason filters::kReasonNoDetector.
#pragma once

#include <string>
#include <utility>

#include "core/config.h"
#include "filters/interaction.h"
#include "stages/stage.h"

namespace doasido::stages {

// The file the detector writes in the stage's artifact folder.
inline constexpr const char* kDetectionsFile = "detections.jsonl";

class ExternalDetectorStage : public Stage {
 public:
  explicit ExternalDetectorStage(filters::ExternalDetectorConfig config = {})
      : config_(std::move(config)) {}
  std::string Name() const override { return filters::kExternalDetectorStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;

 private:
  filters::ExternalDetectorConfig config_;
};

}  // namespace doasido::stages
