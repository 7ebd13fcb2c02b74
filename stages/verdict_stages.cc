#include "stages/verdict_stages.h"

#include "core/error.h"

namespace doasido::stages {

Json CopyAnalysis(const ClipContext& context, const std::string& section) {
  const ErrorSite site{.clip = context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                                                : context.clip.external_id,
                       .file = context.video.path,
                       .field = std::string(filters::kAnalyzeStageName) + "." + section};
  auto it = context.measurements.find(filters::kAnalyzeStageName);
  if (it == context.measurements.end()) {
    throw Error("missing_measurements",
                std::string("stage ") + filters::kAnalyzeStageName + " has not run on this clip",
                site);
  }
  auto shot = context.measurements.find(filters::kShotBoundaryStageName);
  const Json* shot_verdict = shot != context.measurements.end() ? &shot->second : nullptr;
  return filters::VerdictInput(it->second, section, shot_verdict, site);
}

StageResult ToStageResult(filters::FilterVerdict verdict) {
  StageResult result;
  result.verdict = verdict.verdict;
  result.reason = std::move(verdict.reason);
  result.measurements = std::move(verdict.measurements);
  return result;
}

std::set<std::string> MeasuringStages(Database& db, ClipId clip, const std::string& decided_by) {
  std::set<std::string> out;
  const std::string path = std::string("$.") + filters::kNotMeasuredKey + ".stage";
  for (const auto& [stage, m] : db.MeasurementsWhere(clip, path, decided_by)) {
    out.insert(m.at(filters::kNotMeasuredKey).value("measured_by", filters::kAnalyzeStageName));
  }
  return out;
}

ShotBoundaryStage::ShotBoundaryStage(filters::ShotBoundaryConfig config)
    : MeasuredVerdictStage(filters::kShotBoundaryStageName, std::move(config),
                           filters::DecideShots) {}

InteractionStage::InteractionStage(filters::InteractionConfig config)
    : MeasuredVerdictStage(filters::kInteractionStageName, std::move(config),
                           filters::DecideInteraction) {}

OutOfFrameStage::OutOfFrameStage(filters::OutOfFrameConfig config)
    : MeasuredVerdictStage(filters::kOutOfFrameStageName, std::move(config),
                           filters::DecideOutOfFrame) {}

ActivityStage::ActivityStage(filters::ActivityConfig config)
    : MeasuredVerdictStage(filters::kActivityStageName, std::move(config),
                           filters::DecideActivity) {}

CameraMotionStage::CameraMotionStage(filters::CameraMotionConfig config)
    : MeasuredVerdictStage(filters::kCameraMotionStageName, std::move(config),
                           filters::DecideCameraMotion) {}

}  // namespace doasido::stages
