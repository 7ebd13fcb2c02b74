// Stage "filters_analyze": the one decode of a clip that every filter needs
// (filters::AnalyzeClip, filters/analyze.h), over the clip's span, with the
// clip's detections. Its measurements are the analysis's, its verdict is
// always pass, and the boxes a detector found are its
// StageResult::detections (source "detector:learned" or
// "detector:builtin"). The verdict stages (stages/verdict_stages.h) run
// after it and decide from its measurements without decoding.
//
// The clip span is ClipRecord start_frame/end_frame (inclusive), else
// start_s/end_s converted at the stream's frame rate, else the whole file.
#pragma once

#include <string>

#include "core/config.h"
#include "filters/analyze.h"
#include "stages/stage.h"

namespace doasido::stages {

class AnalyzeStage : public Stage {
 public:
  explicit AnalyzeStage(filters::AnalyzeConfig config = {}) : config_(std::move(config)) {}
  // `whole_config`: the configuration file, for the cheap verdicts' sections.
  AnalyzeStage(filters::AnalyzeConfig config, const Json& whole_config);
  std::string Name() const override { return filters::kAnalyzeStageName; }
  // The config, and the cheap verdicts' configs when they decide whether
  // the models run.
  Json Params() const override;
  StageResult Run(const ClipContext& context) override;
  // Builds the learned detector's graphs (native runtime) before the first clip.
  void Prepare() override;

 private:
  filters::AnalyzeConfig config_;
  filters::CheapVerdictConfigs verdicts_;
};

}  // namespace doasido::stages
