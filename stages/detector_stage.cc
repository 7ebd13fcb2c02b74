#include "stages/detector_stage.h"

#include <filesystem>
#include <map>

namespace doasido::stages {

StageResult ExternalDetectorStage::Run(const ClipContext& context) {
  StageResult result;
  if (config_.command.empty()) {
    result.reason = filters::kReasonNoDetector;
    result.measurements = {{"ran", false}};
    return result;
  }
  const std::int64_t first = context.clip.start_frame.value_or(0);
  const std::int64_t last = context.clip.end_frame.value_or(-1);
  std::filesystem::create_directories(context.artifact_dir);
  const auto output = context.artifact_dir / kDetectionsFile;
  const std::string clip =
      context.clip.external_id.empty() ? std::to_string(context.clip.id) : context.clip.external_id;
  result.detections =
      filters::RunExternalDetector(config_, context.video.path, first, last, output, clip);
  std::map<std::int64_t, int> per_frame;
  for (const Detection& d : result.detections) per_frame[d.frame] += d.kind == "hand";
  result.measurements = {
      {"ran", true}, {"detections", result.detections.size()}, {"frames", per_frame.size()}};
  result.artifacts.emplace_back("detections_jsonl", kDetectionsFile);
  return result;
}

}  // namespace doasido::stages
