#include "filters/deferred_hand_models.h"

#include <opencv2/imgproc.hpp>

namespace doasido::filters {

void SampleKeeper::Begin(const VideoGeometry& geometry) {
  every_ = SampleEvery(geometry, config_);
  samples_.clear();
  grays_.clear();
  kept_mb_ = 0;
  grays_overflow_ = false;
}

void SampleKeeper::Consume(FrameContext& context) {
  if (!grays_overflow_) {
    kept_mb_ += context.gray.total() * context.gray.elemSize() / 1e6;
    if (kept_mb_ > config_.keep_mb) {
      grays_overflow_ = true;
      grays_.clear();
      grays_.shrink_to_fit();
    } else {
      grays_.push_back(context.gray.clone());
    }
  }
  if (context.ordinal % every_ != 0) return;
  AnalysisFrame& kept = samples_[context.ordinal];
  kept.index = context.frame->index;
  kept.timestamp_s = context.frame->timestamp_s;
  kept.bgr = context.frame->bgr.clone();  // the decoder reuses its buffer
}

std::optional<CheapRejection> CheapVerdictRejection(const Json& analysis,
                                                    const CheapVerdictConfigs& verdicts,
                                                    const std::string& clip, ShotSpan* kept) {
  // As the verdict stages judge the clip: the shot boundary first, then
  // camera motion on the shot it keeps.
  const auto input = [&](const char* section, const Json* shot_verdict) {
    const ErrorSite site{.clip = clip.empty() ? "0" : clip,
                         .field = std::string(kAnalyzeStageName) + "." + section};
    return VerdictInput(analysis, section, shot_verdict, site);
  };
  const FilterVerdict shot = DecideShots(input(kShotBoundaryStageName, nullptr), verdicts.shot);
  if (shot.verdict == Verdict::kReject) return CheapRejection{kShotBoundaryStageName, shot.reason};
  const FilterVerdict camera =
      DecideCameraMotion(input(kCameraMotionStageName, &shot.measurements), verdicts.camera_motion);
  if (camera.verdict == Verdict::kReject) {
    return CheapRejection{kCameraMotionStageName, camera.reason};
  }
  *kept = SpanOf(camera.measurements, analysis.at("clip").at("frames").get<std::int64_t>());
  return std::nullopt;
}

void MarkHandSectionsNotMeasured(const CheapRejection& rejection, Json* measurements) {
  Json sections = Json::array();
  for (const char* section : {kInteractionStageName, kOutOfFrameStageName, kActivityStageName}) {
    measurements->erase(section);
    sections.push_back(section);
  }
  (*measurements)[kNotMeasuredKey] = {{"stage", rejection.stage},
                                      {"reason", rejection.reason},
                                      {"sections", sections},
                                      {"measured_by", kAnalyzeStageName}};
  (*measurements)["clip"]["detector_note"] =
      "hand models not run: the clip is rejected by " + rejection.stage + " (" +
      rejection.reason + ")";
}

void RunHandModelsOnKeptShot(const SampleKeeper& keeper, const ShotSpan& kept,
                             const VideoGeometry& geometry, const AnalyzeConfig& config,
                             const std::string& clip, ClipAnalysis* out) {
  LearnedHandDetector learned(config.learned_detector, clip, config.activity);
  InteractionExtractor interaction;
  OutOfFrameExtractor out_of_frame(config.out_of_frame);
  ActivityExtractor activity(config.activity);
  const std::int64_t frames = out->measurements.at("clip").at("frames").get<std::int64_t>();
  const bool grays = static_cast<std::int64_t>(keeper.grays().size()) == frames;
  const std::initializer_list<FrameConsumer*> consumers = {&learned, &interaction, &out_of_frame,
                                                           &activity};
  for (FrameConsumer* c : consumers) c->Begin(geometry);
  FrameContext context;
  for (std::int64_t i = 0; i < frames; ++i) {
    context = FrameContext{};
    context.ordinal = i;
    if (kept.Contains(i)) {
      // Between samples the detector only repeats its last boxes; on a
      // sample it needs the kept frame.
      const auto sample = keeper.samples().find(i);
      if (sample != keeper.samples().end()) {
        context.frame = &sample->second;
        cv::cvtColor(sample->second.bgr, context.gray, cv::COLOR_BGR2GRAY);
      }
      if (context.frame != nullptr || i % SampleEvery(geometry, config.learned_detector) != 0) {
        learned.Consume(context);
      }
    }
    interaction.Consume(context);
    out_of_frame.Consume(context);
    if (grays) {
      context.gray = keeper.grays()[i];
      activity.Consume(context);
    }
  }
  for (FrameConsumer* c : consumers) c->Finish();
  Json& m = out->measurements;
  m[kInteractionStageName] = ToJson(interaction.signals());
  m[kOutOfFrameStageName] = ToJson(out_of_frame.signals());
  if (grays) {
    m[kActivityStageName] = ToJson(activity.signals());
  } else {
    m["clip"]["detector_note"] = "activity measured around the built-in detector's boxes: the "
                                 "clip's frames exceed learned_detector.keep_mb";
  }
  m[kHandsMeasurement] = learned.Measurements();
  m["clip"]["detection_source"] = "learned";
  out->builtin_detections = learned.detections();
}

}  // namespace doasido::filters
