// Camera motion: global image motion between frames sampled at ~5 fps.
//
// Why 5 fps: hand-held shake is fast and mean-free, so a slow sampling
// rate aliases it into a small net motion (at 2 fps, 9 of 16 synthetic
// shakes of 0.2-0.4 degrees stayed under the reject level); at 5 and at 10
// fps every synthetic pan, shake and zoom is rejected and no other clip is
// (seeds 23 and 41). 5 fps halves the cost, and the static real clips sit
// further below the flag level: each pair's tracking noise adds to the
// cumulative rates, so half the pairs add half the noise (02_cups'
// translation rate 0.0022 -> 0.0008 diagonals/s, its scale rate 0.0039 ->
// 0.0015), while real camera motion measures the same (bedroom 0.026 ->
// 0.024). The 15-pixel tracking window (half the area of OpenCV's default
// 21) is as large at the analysis size's 256 pixels as 21 is at 360: the
// same verdicts on the labelled real footage and the synthetic seeds, the
// static clips' rates lower still.
//
// Signals (analysis pass): the frames ordinal 0, step, 2*step, ... with
// step = round(fps / sample_fps) are compared pairwise. On the earlier frame,
// Shi-Tomasi corners (max 200, quality 0.01, min distance 7 px; Data-Juicer's
// video_camera_motion_consistency_filter defaults) are found outside the
// hand and object boxes of that frame (grown by box_margin) when boxes are
// known, tracked into the later frame with pyramidal Lucas-Kanade, and a
// global model is fitted by RANSAC: a similarity (default) or a homography,
// with a 3-pixel reprojection threshold at full resolution (similarity by
// default: four parameters stay well-posed with the few background points a
// hand-filled frame leaves). From the model
// each pair records the image-centre translation (fraction of the image
// diagonal, x and y), rotation (radians, counter-clockwise in image
// coordinates) and scale change (log of the area scale's square root), the
// tracked and inlier point counts, and whether the fit succeeded.
//
// Decision (DecideCameraMotion), over the pairs of the kept shot (when the
// shot filter ran first) that keep clear of shot boundaries (by max(3,
// step/2) frames, as a boundary sits in the middle of a dissolve): rates per
// second over the clip (cumulative
// |motion| / clip duration) and peaks (largest per-pair |motion| / pair
// duration) for translation, rotation and scale. Any mean rate or peak at or
// above its reject level: reject "camera_motion"; else any at or above its
// flag level: flag "camera_motion". When fewer than min_valid_fraction of the
// pairs could be fitted the motion is unknown: flag "camera_motion_unknown".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "filters/frame_analyzer.h"
#include "filters/verdict.h"

namespace doasido::filters {

// The stage's name: also its config section and its section of the
// analysis stage's measurements.
inline constexpr const char* kCameraMotionStageName = "camera_motion";
// Reason codes: reject or flag for camera motion; flag when too little of
// the background could be tracked to tell.
inline constexpr const char* kReasonCameraMotion = "camera_motion";
inline constexpr const char* kReasonCameraMotionUnknown = "camera_motion_unknown";

struct CameraMotionSignalConfig {
  double sample_fps = 5.0;
  int max_corners = 200;
  double quality_level = 0.01;
  double min_distance = 7.0;  // analysis pixels
  int lk_window = 15;         // analysis pixels
  int lk_levels = 3;
  // Lucas-Kanade stops a point after lk_iterations steps or a step under
  // lk_epsilon pixels (OpenCV's defaults: 30 and 0.01). Points that do not
  // converge are background RANSAC rejects or hands; 10 steps and 0.03 px
  // (the motion's noise floor at 5 fps is under 0.001 diagonals/s, the
  // flag level 0.004) take a third less time.
  int lk_iterations = 10;
  double lk_epsilon = 0.03;  // analysis pixels
  double ransac_threshold = 3.0;     // full-resolution pixels
  std::string model = "similarity";  // or "homography"
  double box_margin = 0.15;          // grow excluded boxes by this fraction per side
  int min_points = 8;
  // When fewer corners than this lie outside the boxes, corners are taken
  // from the whole frame instead and RANSAC is left to reject the moving
  // ones (boxes from the built-in detector can cover most of the frame).
  int min_background_points = 30;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(CameraMotionSignalConfig, sample_fps, max_corners,
                                                quality_level, min_distance, lk_window, lk_levels,
                                                lk_iterations, lk_epsilon,
                                                ransac_threshold, model, box_margin, min_points,
                                                min_background_points)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const CameraMotionSignalConfig& c, const std::string& section);

struct CameraMotionSignals {
  int step = 1;                     // frames between samples
  std::vector<std::int64_t> frame;  // ordinal of the later frame of each pair
  std::vector<double> dt_s;         // time between the two frames
  std::vector<double> tx, ty;       // centre translation / image diagonal
  std::vector<double> rotation;     // radians
  std::vector<double> log_scale;    // log of scale change
  std::vector<int> points, inliers;
  std::vector<int> valid;   // 1 when the model was fitted
  std::vector<int> masked;  // 1 when corners came from outside the boxes only
};
Json ToJson(const CameraMotionSignals& s);
CameraMotionSignals CameraMotionSignalsFromJson(const Json& j);  // throws Error("bad_measurements")

class CameraMotionExtractor : public FrameConsumer {
 public:
  explicit CameraMotionExtractor(CameraMotionSignalConfig config = {}) : config_(config) {}
  void Begin(const VideoGeometry& geometry) override;
  void Consume(FrameContext& context) override;
  const CameraMotionSignals& signals() const { return signals_; }

 private:
  CameraMotionSignalConfig config_;
  VideoGeometry geometry_;
  CameraMotionSignals signals_;
  cv::Mat prev_gray_, prev_mask_;
  double prev_time_ = 0;
};

struct CameraMotionConfig {
  // Mean rates over the clip (cumulative |motion| per second).
  double reject_translation_rate = 0.008;  // image diagonals per second
  double flag_translation_rate = 0.004;
  double reject_rotation_rate = 0.02;  // radians per second (~1.1 deg/s)
  double flag_rotation_rate = 0.01;
  double reject_scale_rate = 0.015;  // |log scale| per second
  double flag_scale_rate = 0.007;
  // Peaks (largest single pair, per second).
  double reject_peak_translation_rate = 0.30;
  double reject_peak_rotation_rate = 0.35;
  double reject_peak_scale_rate = 0.30;
  double min_valid_fraction = 0.5;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(CameraMotionConfig, reject_translation_rate,
                                                flag_translation_rate, reject_rotation_rate,
                                                flag_rotation_rate, reject_scale_rate,
                                                flag_scale_rate, reject_peak_translation_rate,
                                                reject_peak_rotation_rate, reject_peak_scale_rate,
                                                min_valid_fraction)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const CameraMotionConfig& c, const std::string& section);

// Summary numbers of a clip's camera motion (see the file comment).
struct CameraMotionSummary {
  double duration_s = 0;
  double cumulative_translation = 0, cumulative_rotation = 0, cumulative_scale = 0;
  double net_translation = 0;  // |sum of translations|
  double translation_rate = 0, rotation_rate = 0, scale_rate = 0;
  double peak_translation_rate = 0, peak_rotation_rate = 0, peak_scale_rate = 0;
  double mean_inlier_ratio = 0;
  double valid_fraction = 0;
  int pairs = 0;
};
// Over the pairs inside `span` that do not straddle one of its boundaries.
CameraMotionSummary SummarizeCameraMotion(const CameraMotionSignals& s, const ShotSpan& span);

// The rule of stage "camera_motion" (see the file comment) on its
// measurements {"clip", "signals": the "camera_motion" section of the
// analysis, "shot"} (filters/verdict.h): reject or flag "camera_motion",
// flag "camera_motion_unknown", else pass. Throws Error("bad_measurements")
// when they lack a field it reads.
FilterVerdict DecideCameraMotion(const Json& measurements, const CameraMotionConfig& config);

}  // namespace doasido::filters
