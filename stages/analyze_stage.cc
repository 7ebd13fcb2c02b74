#include "stages/analyze_stage.h"

#include "core/config_check.h"

namespace doasido::stages {

AnalyzeStage::AnalyzeStage(filters::AnalyzeConfig config, const Json& whole_config)
    : config_(std::move(config)) {
  ReadCheckedSection(whole_config, filters::kShotBoundaryStageName, verdicts_.shot);
  ReadCheckedSection(whole_config, filters::kCameraMotionStageName, verdicts_.camera_motion);
}

Json AnalyzeStage::Params() const {
  Json params = config_;
  if (config_.hand_detector == "learned" && config_.learned_detector.after_cheap_verdicts) {
    params["cheap_verdicts"] = {{filters::kShotBoundaryStageName, verdicts_.shot},
                                {filters::kCameraMotionStageName, verdicts_.camera_motion}};
  }
  return params;
}

void AnalyzeStage::Prepare() {
  const filters::LearnedDetectorConfig& learned = config_.learned_detector;
  if (config_.use_builtin_detector && config_.hand_detector == "learned" &&
      learned.backend == filters::kBackendNative) {
    filters::PrepareHandModels(learned.models);  // a failure falls back on the first clip
  }
}

StageResult AnalyzeStage::Run(const ClipContext& context) {
  DecoderOptions options;
  options.clip =
      context.clip.external_id.empty() ? std::to_string(context.clip.id) : context.clip.external_id;
  if (context.clip.start_frame) {
    options.first_frame = *context.clip.start_frame;
  } else if (context.clip.start_s) {
    options.first_s = *context.clip.start_s;
  }
  if (context.clip.end_frame) {
    options.last_frame = *context.clip.end_frame;
  } else if (context.clip.end_s) {
    options.last_s = *context.clip.end_s;
  }
  filters::ClipAnalysis analysis =
      filters::AnalyzeClip(context.video.path, options, context.detections, config_, verdicts_);
  StageResult result;
  result.measurements = std::move(analysis.measurements);
  result.detections = std::move(analysis.builtin_detections);
  return result;
}

}  // namespace doasido::stages
