#include "filters/analyze.h"

#include <memory>

#include "core/error.h"
#include "filters/deferred_hand_models.h"
#include "filters/verdict.h"

namespace doasido::filters {

ClipAnalysis AnalyzeClip(const std::filesystem::path& video, const DecoderOptions& options,
                         const std::vector<Detection>& detections, const AnalyzeConfig& config,
                         const CheapVerdictConfigs& verdicts) {
  DecoderOptions decode = options;
  decode.analysis_size = config.analysis_size;
  decode.frame_count_tolerance = config.frame_count_tolerance;
  if (config.decode != "exact" && config.decode != "fast") {
    throw Error("bad_config", "decode must be \"exact\" or \"fast\", not \"" + config.decode + "\"",
                {.clip = options.clip, .field = "filters_analyze.decode"});
  }
  decode.exact_scaling = config.decode == "exact";
  decode.skip_loop_filter = config.decode == "fast";

  const bool detect = detections.empty() && config.use_builtin_detector;
  std::string note;
  std::unique_ptr<LearnedHandDetector> learned;
  bool deferred = false;  // the models run after the cheap verdicts
  if (detect && config.hand_detector == "learned") {
    if (!HandLandmarkerAvailable(&note)) {
      note = "learned detector unavailable: " + note;
    } else if (config.learned_detector.after_cheap_verdicts) {
      deferred = true;
    } else {
      learned = std::make_unique<LearnedHandDetector>(config.learned_detector, options.clip,
                                                        config.activity);
    }
  }
  const bool builtin = detect && !learned;
  SampleKeeper keeper(config.learned_detector);
  BuiltinHandObjectDetector detector(config.detector);
  InteractionExtractor interaction;
  OutOfFrameExtractor out_of_frame(config.out_of_frame);
  ShotSignalExtractor shots(config.shot);
  ActivityExtractor activity(config.activity);
  CameraMotionExtractor camera(config.camera_motion);
  std::vector<FrameConsumer*> consumers;
  if (deferred) consumers.push_back(&keeper);
  if (learned) consumers.push_back(learned.get());
  if (builtin) consumers.push_back(&detector);
  for (FrameConsumer* c : std::initializer_list<FrameConsumer*>{&interaction, &out_of_frame, &shots,
                                                                &activity, &camera}) {
    consumers.push_back(c);
  }
  const AnalysisSummary summary = AnalyzeFrames(video, decode, detections, consumers);

  ClipAnalysis out;
  const VideoGeometry& g = summary.geometry;
  out.measurements = {
      {"clip",
       {{"first_frame", summary.first_frame},
        {"frames", summary.frames},
        {"fps", g.fps},
        {"width", g.width},
        {"height", g.height},
        {"full_width", g.full_width},
        {"full_height", g.full_height},
        {"downscale", g.downscale},
        {"detection_source", learned   ? "learned"
                             : builtin ? "builtin"
                                       : (detections.empty() ? "none" : "clip")}}},
      {kShotBoundaryStageName, ToJson(shots.signals())},
      {kActivityStageName, ToJson(activity.signals())},
      {kCameraMotionStageName, ToJson(camera.signals())},
      {kOutOfFrameStageName, ToJson(out_of_frame.signals())},
      {kInteractionStageName, ToJson(interaction.signals())}};
  if (!note.empty()) out.measurements["clip"]["detector_note"] = note;
  if (learned) {
    out.measurements[kHandsMeasurement] = learned->Measurements();
    out.builtin_detections = learned->detections();
  }
  if (builtin) out.builtin_detections = detector.detections();
  if (deferred) {
    ShotSpan kept;
    const auto rejected = CheapVerdictRejection(out.measurements, verdicts, options.clip, &kept);
    if (!rejected) {
      RunHandModelsOnKeptShot(keeper, kept, g, config, options.clip, &out);
    } else {
      MarkHandSectionsNotMeasured(*rejected, &out.measurements);
      // The built-in boxes only masked the hands for camera motion: they
      // are no hand evidence, and stored they would be read as the clip's
      // own boxes when the clip is measured again (rethreshold).
      out.builtin_detections.clear();
    }
  }
  return out;
}

}  // namespace doasido::filters
