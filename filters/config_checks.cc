// The valid ranges of every filter's parameters, checked when a
// configuration is loaded (core/config_check.h). Fractions are of frames or
// of the image; thresholds on 8-bit levels lie in [0, 255].
#include <string>

#include "core/config_check.h"
#include "filters/activity.h"
#include "filters/analyze.h"
#include "filters/camera_motion.h"
#include "filters/interaction.h"
#include "filters/hand_models.h"
#include "filters/learned_hand_detector.h"
#include "filters/out_of_frame.h"
#include "filters/shot_boundary.h"

namespace doasido::filters {
namespace {

constexpr double kLevels = 255;     // 8-bit intensity or colour difference
constexpr double kMany = 1e6;       // counts and frame numbers with no natural bound
constexpr double kNeverAbove = 2;   // fraction thresholds above 1 never trigger

void RequireFraction(const std::string& section, const std::string& key, double value) {
  RequireInRange(section, key, value, 0, 1);
}

}  // namespace

void CheckConfig(const ShotSignalConfig& c, const std::string& section) {
  RequireInRange(section, "hash_size", c.hash_size, 2, 256);
  RequireInRange(section, "hash_lowpass", c.hash_lowpass, 1, 16);
  RequireInRange(section, "histogram_bins", c.histogram_bins, 2, 256);
  RequireInRange(section, "long_window_s", c.long_window_s, 0, 60);
  RequireInRange(section, "blend_step", c.blend_step, 1, 100);
  RequireInRange(section, "blend_change_level", c.blend_change_level, 0, kLevels);
  RequireFraction(section, "blend_tolerance", c.blend_tolerance);
}

void CheckConfig(const ShotBoundaryConfig& c, const std::string& section) {
  RequireInRange(section, "content_threshold", c.content_threshold, 0, kLevels);
  RequireInRange(section, "weight_hue", c.weight_hue, 0, 100);
  RequireInRange(section, "weight_sat", c.weight_sat, 0, 100);
  RequireInRange(section, "weight_lum", c.weight_lum, 0, 100);
  RequireInRange(section, "min_scene_len", c.min_scene_len, 1, kMany);
  RequireInRange(section, "adaptive_threshold", c.adaptive_threshold, 0, 100);
  RequireInRange(section, "min_content_val", c.min_content_val, 0, kLevels);
  RequireInRange(section, "window_width", c.window_width, 1, 100);
  RequireFraction(section, "hash_threshold", c.hash_threshold);
  RequireFraction(section, "histogram_threshold", c.histogram_threshold);
  RequireInRange(section, "fade_threshold", c.fade_threshold, 0, kLevels);
  RequireInRange(section, "fade_bias", c.fade_bias, -1, 1);  // PySceneDetect's range
  RequireFraction(section, "dissolve_threshold", c.dissolve_threshold);
  RequireFraction(section, "dissolve_steady", c.dissolve_steady);
  RequireFraction(section, "blend_min_changed", c.blend_min_changed);
  RequireFraction(section, "blend_max_unexplained", c.blend_max_unexplained);
  RequireInRange(section, "blend_min_run", c.blend_min_run, 1, 1000);
  for (const auto& name : c.boundary_detectors) {
    RequireOneOf(section, "boundary_detectors", name,
                 {"content", "adaptive", "hash", "histogram", "dissolve", "fade"});
  }
  RequireInRange(section, "min_segment_s", c.min_segment_s, 0, 3600);
}

void CheckConfig(const OutOfFrameSignalConfig& c, const std::string& section) {
  RequireInRange(section, "border_margin", c.border_margin, 0, 0.5);
}

void CheckConfig(const OutOfFrameConfig& c, const std::string& section) {
  RequireInRange(section, "reject_missing_fraction", c.reject_missing_fraction, 0, kNeverAbove);
  RequireInRange(section, "flag_missing_fraction", c.flag_missing_fraction, 0, kNeverAbove);
  RequireInRange(section, "reject_cut_fraction", c.reject_cut_fraction, 0, kNeverAbove);
  RequireInRange(section, "flag_cut_fraction", c.flag_cut_fraction, 0, kNeverAbove);
  RequireFraction(section, "min_covered_fraction", c.min_covered_fraction);
}

void CheckConfig(const ActivitySignalConfig& c, const std::string& section) {
  RequireInRange(section, "box_margin", c.box_margin, 0, 2);
  RequireInRange(section, "pixel_threshold", c.pixel_threshold, 0, kLevels);
}

void CheckConfig(const ActivityConfig& c, const std::string& section) {
  RequireFraction(section, "min_moving_fraction", c.min_moving_fraction);
  RequireFraction(section, "min_active_fraction", c.min_active_fraction);
}

void CheckConfig(const CameraMotionSignalConfig& c, const std::string& section) {
  RequireInRange(section, "sample_fps", c.sample_fps, 1e-3, 1000);
  RequireInRange(section, "max_corners", c.max_corners, 1, kMany);
  RequireInRange(section, "quality_level", c.quality_level, 1e-6, 1);
  RequireInRange(section, "min_distance", c.min_distance, 0, 1000);
  RequireInRange(section, "lk_window", c.lk_window, 3, 201);
  RequireInRange(section, "lk_levels", c.lk_levels, 0, 10);
  RequireInRange(section, "lk_iterations", c.lk_iterations, 1, 1000);
  RequireInRange(section, "lk_epsilon", c.lk_epsilon, 1e-6, 10);
  RequireInRange(section, "ransac_threshold", c.ransac_threshold, 0, 1000);
  RequireOneOf(section, "model", c.model, {"similarity", "homography"});
  RequireInRange(section, "box_margin", c.box_margin, 0, 2);
  RequireInRange(section, "min_points", c.min_points, 3, kMany);
  RequireInRange(section, "min_background_points", c.min_background_points, 0, kMany);
}

void CheckConfig(const CameraMotionConfig& c, const std::string& section) {
  // Rates are image diagonals, radians or |log scale| per second.
  RequireInRange(section, "reject_translation_rate", c.reject_translation_rate, 0, 100);
  RequireInRange(section, "flag_translation_rate", c.flag_translation_rate, 0, 100);
  RequireInRange(section, "reject_rotation_rate", c.reject_rotation_rate, 0, 100);
  RequireInRange(section, "flag_rotation_rate", c.flag_rotation_rate, 0, 100);
  RequireInRange(section, "reject_scale_rate", c.reject_scale_rate, 0, 100);
  RequireInRange(section, "flag_scale_rate", c.flag_scale_rate, 0, 100);
  RequireInRange(section, "reject_peak_translation_rate", c.reject_peak_translation_rate, 0, 100);
  RequireInRange(section, "reject_peak_rotation_rate", c.reject_peak_rotation_rate, 0, 100);
  RequireInRange(section, "reject_peak_scale_rate", c.reject_peak_scale_rate, 0, 100);
  RequireFraction(section, "min_valid_fraction", c.min_valid_fraction);
}

void CheckConfig(const BuiltinDetectorConfig& c, const std::string& section) {
  RequireInRange(section, "y_min", c.y_min, 0, kLevels);
  RequireInRange(section, "cr_min", c.cr_min, 0, kLevels);
  RequireInRange(section, "cr_max", c.cr_max, c.cr_min, kLevels);
  RequireInRange(section, "cb_min", c.cb_min, 0, kLevels);
  RequireInRange(section, "cb_max", c.cb_max, c.cb_min, kLevels);
  RequireInRange(section, "motion_threshold", c.motion_threshold, 0, kLevels);
  RequireInRange(section, "motion_gap", c.motion_gap, 1, 100);
  RequireFraction(section, "min_hand_area", c.min_hand_area);
  RequireInRange(section, "max_hand_area", c.max_hand_area, c.min_hand_area, 1);
  RequireFraction(section, "min_hand_motion", c.min_hand_motion);
  RequireFraction(section, "min_object_area", c.min_object_area);
  RequireFraction(section, "contact_distance", c.contact_distance);
  RequireInRange(section, "max_hands", c.max_hands, 0, 10);
  RequireInRange(section, "hold_frames", c.hold_frames, 0, kMany);
  RequireFraction(section, "global_motion_fraction", c.global_motion_fraction);
}

void CheckConfig(const InteractionConfig& c, const std::string& section) {
  for (int state : c.contact_states) {
    RequireInRange(section, "contact_states", state, 0, 4);  // 100DOH's N, S, O, P, F
  }
  RequireFraction(section, "min_interaction_fraction", c.min_interaction_fraction);
  RequireFraction(section, "min_covered_fraction", c.min_covered_fraction);
}

void CheckConfig(const ExternalDetectorConfig& c, const std::string& section) {
  RequireFraction(section, "min_score", c.min_score);
}

void CheckConfig(const AnalyzeConfig& c, const std::string& section) {
  RequireInRange(section, "analysis_size", c.analysis_size, 16, 8192);
  RequireOneOf(section, "decode", c.decode, {"exact", "fast"});
  RequireInRange(section, "frame_count_tolerance", static_cast<double>(c.frame_count_tolerance),
                 0, kMany);
  CheckConfig(c.shot, section + ".shot");
  CheckConfig(c.activity, section + ".activity");
  CheckConfig(c.camera_motion, section + ".camera_motion");
  CheckConfig(c.out_of_frame, section + ".out_of_frame");
  RequireOneOf(section, "hand_detector", c.hand_detector, {"learned", "builtin"});
  CheckConfig(c.detector, section + ".detector");
  CheckConfig(c.learned_detector, section + ".learned_detector");
}

void CheckConfig(const LearnedDetectorConfig& c, const std::string& section) {
  RequireInRange(section, "sample_fps", c.sample_fps, 0.1, 1000);
  RequireInRange(section, "max_hands", c.max_hands, 1, 8);
  RequireFraction(section, "min_score", c.min_score);
  RequireInRange(section, "fingertip_reach", c.fingertip_reach, 0.01, 5);
  RequireInRange(section, "hand_thickness", c.hand_thickness, 0.01, 5);
  RequireFraction(section, "min_object_edges", c.min_object_edges);
  RequireInRange(section, "hold_samples", c.hold_samples, 0, 100);
  RequireFraction(section, "border_reach", c.border_reach);
  RequireOneOf(section, "backend", c.backend, {"native", "wasm"});
  RequireOneOf(section, "models", c.models, {kModelsFull, kModelsLite, kModelsLiteLandmark});
  RequireInRange(section, "keep_mb", c.keep_mb, 1, 1e6);
  RequireInRange(section, "palm_every", c.palm_every, 1, 1000);
  RequireInRange(section, "still_sample_fps", c.still_sample_fps, 0.01, 1000);
  if (c.still_sample_fps > c.sample_fps) {
    throw Error("bad_config",
                section + ".still_sample_fps (" + std::to_string(c.still_sample_fps) +
                    ") must not exceed sample_fps (" + std::to_string(c.sample_fps) +
                    "): it is the rate where nothing moves; equal turns the thinning off",
                {.field = section + ".still_sample_fps"});
  }
  RequireFraction(section, "still_changed_fraction", c.still_changed_fraction);
  RequireInRange(section, "no_hand_palm_every", c.no_hand_palm_every, 1, 1000);
  RequireFraction(section, "no_hand_changed_fraction", c.no_hand_changed_fraction);
}

}  // namespace doasido::filters
