// The analysis: the one decode of a clip that every filter needs (stage
// "filters_analyze", stages/analyze_stage.h, runs it in the queue).
//
// It decodes the clip's span once at analysis resolution and runs, per
// frame and in this order: a hand/object detector (only when the clip has no
// detections and use_builtin_detector is set: the learned one, or the
// built-in one, see hand_detector), then the signal
// extractors of the interaction, out-of-frame, shot-boundary, activity and
// camera-motion filters. Its measurements are
//   {"clip": {first_frame, frames, fps, width, height, full_width,
//             full_height, downscale, detection_source (clip, learned,
//             builtin or none), detector_note (why not learned)},
//    "hands": {...} (the learned detector's samples with keypoints, when it ran),
//    "shot_boundary": {...}, "activity": {...}, "camera_motion": {...},
//    "out_of_frame": {...}, "interaction": {...}}
// and the five verdict rules (DecideShots, DecideActivity,
// DecideCameraMotion, DecideOutOfFrame, DecideInteraction) decide from
// these measurements without decoding.
//
// A missing, unreadable or truncated file throws Error naming the clip, the
// file and the frame (video/video_decoder.h).
#pragma once

#include <string>

#include "core/config.h"
#include "filters/activity.h"
#include "filters/camera_motion.h"
#include "filters/interaction.h"
#include "filters/learned_hand_detector.h"
#include "filters/out_of_frame.h"
#include "filters/shot_boundary.h"
#include "filters/verdict.h"

namespace doasido::filters {

struct AnalyzeConfig {
  int analysis_size = 256;  // longer side, PySceneDetect's default
  // "exact": PySceneDetect's pixels (deblocked decode, full-size BGR,
  // cv::resize), so shot scores equal its published ones. "fast": no
  // deblocking, YUV scaled straight to analysis size (video/video_decoder.h);
  // scores move by a few per cent, which can move cuts whose score sits at
  // a threshold (testvideo: 211 and 691).
  std::string decode = "exact";
  bool use_builtin_detector = true;  // false: no detector runs on clips without boxes
  // Which detector a clip without boxes gets: "learned" (MediaPipe Hands,
  // filters/learned_hand_detector.h; falls back to "builtin", saying why in
  // clip.detector_note, when node or its npm packages are missing) or
  // "builtin" (the skin-and-motion detector of filters/interaction.h).
  std::string hand_detector = "learned";
  std::int64_t frame_count_tolerance = 0;
  ShotSignalConfig shot;
  ActivitySignalConfig activity;
  CameraMotionSignalConfig camera_motion;
  OutOfFrameSignalConfig out_of_frame;
  BuiltinDetectorConfig detector;
  LearnedDetectorConfig learned_detector;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(AnalyzeConfig, analysis_size, decode,
                                                use_builtin_detector, hand_detector,
                                                frame_count_tolerance, shot, activity,
                                                camera_motion, out_of_frame, detector,
                                                learned_detector)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const AnalyzeConfig& c, const std::string& section);

// The verdicts the analysis applies itself before it pays for the hand
// models (filters/deferred_hand_models.h), configured as their stages are.
struct CheapVerdictConfigs {
  ShotBoundaryConfig shot;
  CameraMotionConfig camera_motion;
};

// Everything one analysis pass produced (the filters_analyze stage stores
// it; benchmarks and tests call AnalyzeClip directly).
struct ClipAnalysis {
  Json measurements;                          // see the file comment
  std::vector<Detection> builtin_detections;  // the detector's boxes; empty when none ran
};

// Decodes `video` over the span in `options` once and computes every
// filter's signals. `detections` are the clip's boxes (full-resolution file
// frames); when empty and config.use_builtin_detector, the built-in detector
// supplies them (the learned one only on clips `verdicts` keep, when
// config.learned_detector.after_cheap_verdicts).
ClipAnalysis AnalyzeClip(const std::filesystem::path& video, const DecoderOptions& options,
                         const std::vector<Detection>& detections, const AnalyzeConfig& config,
                         const CheapVerdictConfigs& verdicts = {});

}  // namespace doasido::filters
