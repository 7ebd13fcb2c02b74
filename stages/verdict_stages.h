// The filters' verdict stages: shot_boundary, interaction, out_of_frame,
// activity and camera_motion. Each runs its filter's rule (the Decide*
// functions of filters/*.h) on its section of the filters_analyze stage's
// measurements and never decodes; their names, reason codes and configs are
// the filters' (filters/README.md).
#pragma once

#include <optional>
#include <set>
#include <string>
#include <utility>

#include "core/config.h"
#include "db/database.h"
#include "filters/activity.h"
#include "filters/camera_motion.h"
#include "filters/interaction.h"
#include "filters/out_of_frame.h"
#include "filters/shot_boundary.h"
#include "filters/verdict.h"
#include "stages/stage.h"

namespace doasido::stages {

// The input of the rule of stage `section` (filters::VerdictInput) from the
// measurements in `context`: the analysis stage's section, with the kept
// shot when the shot-boundary stage ran before. Throws
// Error("missing_measurements") naming the clip and the file when the
// analysis stage has not run or lacks `section`.
Json CopyAnalysis(const ClipContext& context, const std::string& section);

// A filter's verdict as the queue records it.
StageResult ToStageResult(filters::FilterVerdict verdict);

// The stages to run again for the clip's measurements that the verdict of
// stage `decided_by` made unnecessary (the analysis's, and its
// not_measured runs', filters::kNotMeasuredKey naming `decided_by`): their
// "measured_by". Empty when that verdict left nothing unmeasured.
std::set<std::string> MeasuringStages(Database& db, ClipId clip, const std::string& decided_by);

// A verdict stage that decides from the analysis stage's measurements only
// (never decodes): Run copies the stage's section of them, with the kept
// shot, and applies `rule`; Redecide applies `rule` to stored measurements,
// so `doasido rethreshold` re-derives the verdict without the video. The
// stage's name is also its section in the analysis measurements. When the
// analysis did not measure that section (filters::kNotMeasuredKey), both
// record not_measured instead, naming the verdict that decided the clip.
template <typename Config>
class MeasuredVerdictStage : public Stage {
 public:
  using Rule = filters::FilterVerdict (*)(const Json& measurements, const Config& config);
  MeasuredVerdictStage(std::string name, Config config, Rule rule)
      : name_(std::move(name)), config_(std::move(config)), rule_(rule) {}
  std::string Name() const override { return name_; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override {
    return Decide(CopyAnalysis(context, name_));
  }
  std::optional<StageResult> Redecide(const Json& measurements) const override {
    return Decide(measurements);
  }

 private:
  // Never a verdict from a measurement that did not run (not_measured).
  StageResult Decide(const Json& input) const {
    if (auto unmeasured = filters::NotMeasured(input)) return ToStageResult(std::move(*unmeasured));
    return ToStageResult(rule_(input, config_));
  }

  std::string name_;
  Config config_;
  Rule rule_;
};

// Stage "shot_boundary": filters::DecideShots.
class ShotBoundaryStage : public MeasuredVerdictStage<filters::ShotBoundaryConfig> {
 public:
  explicit ShotBoundaryStage(filters::ShotBoundaryConfig config = {});
};

// Stage "interaction": filters::DecideInteraction.
class InteractionStage : public MeasuredVerdictStage<filters::InteractionConfig> {
 public:
  explicit InteractionStage(filters::InteractionConfig config = {});
};

// Stage "out_of_frame": filters::DecideOutOfFrame.
class OutOfFrameStage : public MeasuredVerdictStage<filters::OutOfFrameConfig> {
 public:
  explicit OutOfFrameStage(filters::OutOfFrameConfig config = {});
};

// Stage "activity": filters::DecideActivity.
class ActivityStage : public MeasuredVerdictStage<filters::ActivityConfig> {
 public:
  explicit ActivityStage(filters::ActivityConfig config = {});
};

// Stage "camera_motion": filters::DecideCameraMotion.
class CameraMotionStage : public MeasuredVerdictStage<filters::CameraMotionConfig> {
 public:
  explicit CameraMotionStage(filters::CameraMotionConfig config = {});
};

}  // namespace doasido::stages
