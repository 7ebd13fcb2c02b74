// Shot boundaries and fades, scored as PySceneDetect scores them.
//
// Per-frame signals (computed once, in the analysis pass, on frames
// downscaled as PySceneDetect downscales them; see video/video_decoder.h):
//   - delta_hue/sat/lum: mean |difference| of each HSV channel (OpenCV 8-bit
//     HSV, hue 0..179) against the previous frame (ContentDetector).
//   - hash_distance: Hamming distance / size^2 between perceptual hashes of
//     consecutive frames: gray, INTER_AREA to (size*lowpass)^2, scaled to
//     max 1, DCT, top-left size x size block, bits above its median
//     (HashDetector).
//   - histogram_correlation: correlation of the L2-normalised 256-bin
//     histograms of the Y (YUV) channel of consecutive frames
//     (HistogramDetector).
//   - mean_intensity: mean of all B, G, R values (ThresholdDetector).
//   - histogram_correlation_long: the same correlation between frame t and
//     frame t - long_window, long_window = round(long_window_s * fps) >= 2
//     (1 for the first long_window frames).
//   - blend_changed / blend_unexplained (linear-blend test, k = blend_step
//     frames): entry t describes frame c = t - k (both 0 resp. 1 for t < 2k).
//     A pixel changed when |gray(c + k) - gray(c - k)| > blend_change_level;
//     a changed pixel is explained when |gray(c) - (gray(c - k) + gray(c +
//     k)) / 2| <= blend_tolerance * |gray(c + k) - gray(c - k)|.
//     blend_changed = changed pixels / pixels, blend_unexplained = 1 -
//     explained / changed pixels (1 when none changed). Inside a dissolve
//     (or a fade to black) every frame is the average of its neighbours, so
//     only the scene's own motion is unexplained; motion (hands, a moving
//     camera, a cut) leaves most changed pixels unexplained: a pixel that a
//     moving edge crosses holds one side's value, half the change off.
//   - changed_fraction_long: fraction of pixels whose gray level differs by
//     more than 25 between frame t and frame t - long_window (0 for the
//     first long_window frames). A dissolve changes almost every pixel of a
//     static shot over a few frames, which no consecutive-frame score sees;
//     a moving hand changes only its own part of the picture.
// Frame 0 has deltas 0, hash distance 0 and correlation 1.
//
// Cut lists are decided from those stored signals alone, so re-thresholding
// never decodes. Every cut is the first frame of the new shot. The state
// machines are PySceneDetect's:
//   - content: score = sum(w_c * delta_c) / sum(|w_c|), above when >= the
//     threshold; min_scene_len is enforced by its flash filter in merge
//     mode: an above-threshold frame is a cut when the previous
//     above-threshold frame (or the first frame) is at least min_scene_len
//     frames back; after the first cut, a burst of closer above-threshold
//     frames is merged and reported at its last above-threshold frame once
//     the burst is at least min_scene_len long and min_scene_len frames
//     below threshold have followed.
//   - adaptive: ratio of a frame's content score to the mean of the
//     `window` scores either side (self excluded; 255 when that mean is 0
//     and the score is >= min_content_val, capped at 255); a cut at the
//     centre frame c when ratio >= adaptive_threshold and score >=
//     min_content_val, and the frame being read (c + window) is at least
//     min_scene_len frames after the previous cut (or the first frame).
//   - hash / histogram: cut when distance >= threshold (correlation <=
//     1 - threshold) and at least min_scene_len frames after the previous
//     cut (or the first frame).
//   - dissolve (doasido's own, not PySceneDetect's): each run of frames whose
//     long-window changed fraction is >= dissolve_threshold gives one cut, at
//     the run's peak minus half the window, if the stretch of unsteady frames
//     (changed fraction > dissolve_steady) around that peak lasts at most two
//     windows (a dissolve joins two steady shots; a moving camera keeps
//     changing) and the cut is at least min_scene_len frames after the
//     previous cut (or the first frame).
//   - dissolve also takes the cuts of BlendCuts (linear-blend runs); the
//     two lists are merged in frame order, dropping a cut within
//     long_window frames of a hard cut (the adaptive detector's: a hard cut
//     changes every pixel against the frame a window back too, which put a
//     spurious dissolve a few frames before each real cut) and a cut closer
//     than min_scene_len to the previous kept one.
//   - fade: a frame is dark when its mean intensity < threshold; on the
//     first bright frame after a dark run that started at frame `out` (the
//     first frame counts as a fade-out when dark) the cut is the midpoint
//     (in + out + bias * (in - out)) / 2 rounded half up, if the fade-in
//     frame is at least min_scene_len frames after the previous fade-in (or
//     the first frame).
//
// Policy (DecideShots): boundaries are the union of the cut lists
// named in `boundary_detectors`; when "fade" is among them, the end of a
// dark run at the clip's start and the beginning of a dark run at its end
// are boundaries too (the clip fades in from or out to black). No boundary:
// pass. Otherwise the clip is trimmed to its longest segment when that lasts
// >= min_segment_s (pass, reason "trimmed", trim recorded), else reject
// "shot_boundary".
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "filters/frame_analyzer.h"
#include "filters/verdict.h"

namespace doasido::filters {

// The stage's name: also its config section and its section of the
// analysis stage's measurements.
inline constexpr const char* kShotBoundaryStageName = "shot_boundary";
// Reason codes: pass trimmed to the longest shot; reject across a cut.
inline constexpr const char* kReasonTrimmed = "trimmed";
inline constexpr const char* kReasonShotBoundary = "shot_boundary";

struct ShotBoundaryConfig {
  // ContentDetector (PySceneDetect defaults; edges are not computed, so
  // their weight is always 0).
  double content_threshold = 27.0;
  double weight_hue = 1.0;
  double weight_sat = 1.0;
  double weight_lum = 1.0;
  // Shared by every detector, in frames.
  int min_scene_len = 15;
  // AdaptiveDetector.
  double adaptive_threshold = 3.0;
  double min_content_val = 15.0;
  int window_width = 2;
  // HashDetector and HistogramDetector.
  double hash_threshold = 0.395;
  double histogram_threshold = 0.05;
  // ThresholdDetector (fades to black).
  double fade_threshold = 12.0;
  double fade_bias = 0.0;
  // Dissolves (long-window histogram correlation).
  double dissolve_threshold = 0.5;
  double dissolve_steady = 0.3;
  // Dissolves (linear-blend test, see BlendCuts).
  double blend_min_changed = 0.2;
  double blend_max_unexplained = 0.4;
  int blend_min_run = 3;
  // Policy. Names: "content", "adaptive", "hash", "histogram", "dissolve", "fade".
  std::vector<std::string> boundary_detectors = {"adaptive", "dissolve", "fade"};
  double min_segment_s = 2.0;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ShotBoundaryConfig, content_threshold, weight_hue,
                                                weight_sat, weight_lum, min_scene_len,
                                                adaptive_threshold, min_content_val, window_width,
                                                hash_threshold, histogram_threshold, fade_threshold,
                                                fade_bias, dissolve_threshold, dissolve_steady,
                                                blend_min_changed, blend_max_unexplained,
                                                blend_min_run, boundary_detectors, min_segment_s)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const ShotBoundaryConfig& c, const std::string& section);

// Analysis-pass parameters of the shot signals.
struct ShotSignalConfig {
  int hash_size = 16;
  int hash_lowpass = 2;
  int histogram_bins = 256;
  double long_window_s = 0.5;  // for histogram_correlation_long (>= 2 frames)
  // Linear-blend test (see blend_changed / blend_unexplained).
  int blend_step = 3;            // frames, >= 1
  int blend_change_level = 12;   // gray levels
  double blend_tolerance = 0.25;  // of a pixel's change
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ShotSignalConfig, hash_size, hash_lowpass,
                                                histogram_bins, long_window_s, blend_step,
                                                blend_change_level, blend_tolerance)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const ShotSignalConfig& c, const std::string& section);

struct ShotSignals {
  std::vector<double> delta_hue, delta_sat, delta_lum;
  std::vector<double> hash_distance;
  std::vector<double> histogram_correlation;
  std::vector<double> mean_intensity;
  std::vector<double> histogram_correlation_long;
  std::vector<double> changed_fraction_long;
  // Linear-blend test of the frame blend_step frames back (see BlendCuts);
  // empty in measurements recorded before the test existed.
  std::vector<double> blend_changed, blend_unexplained;
  int long_window = 15;
  int blend_step = 3;
};
Json ToJson(const ShotSignals& s);
ShotSignals ShotSignalsFromJson(const Json& j);  // throws Error("bad_measurements")

// The Y channel of OpenCV's COLOR_BGR2YUV for an 8-bit BGR image (BT.601 in
// 14-bit fixed point with its rounding: equal for every one of the 2^24
// colours), without making the U and V the histogram does not use.
void Luma(const cv::Mat& bgr, cv::Mat* y);

class ShotSignalExtractor : public FrameConsumer {
 public:
  explicit ShotSignalExtractor(ShotSignalConfig config = {}) : config_(config) {}
  void Begin(const VideoGeometry& geometry) override;
  void Consume(FrameContext& context) override;
  const ShotSignals& signals() const { return signals_; }

 private:
  // The steps of Consume, one signal group each, in PySceneDetect's order.
  void ColourSignals(const cv::Mat& bgr);
  void HashSignal(const cv::Mat& gray);
  void HistogramSignals(const cv::Mat& bgr);
  void ChangedLongSignal(const cv::Mat& gray);
  void BlendSignal();
  cv::Mat Hash(const cv::Mat& gray) const;
  ShotSignalConfig config_;
  ShotSignals signals_;
  cv::Mat hsv_, prev_hsv_, diff_, prev_hash_, prev_hist_, luma_;
  std::deque<cv::Mat> hist_window_, gray_window_;
  std::deque<cv::Mat> blend_window_;
  cv::Mat blend_sum_, blend_mid_, blend_diff_;
};

// Cut lists from stored signals; indices are 0-based positions in the span.
std::vector<double> ContentScores(const ShotSignals& s, const ShotBoundaryConfig& c);
std::vector<std::int64_t> ContentCuts(const std::vector<double>& scores, double threshold,
                                      int min_scene_len);
std::vector<std::int64_t> AdaptiveCuts(const std::vector<double>& scores, double adaptive_threshold,
                                       double min_content_val, int window_width, int min_scene_len);
std::vector<std::int64_t> HashCuts(const std::vector<double>& distance, double threshold,
                                   int min_scene_len);
std::vector<std::int64_t> HistogramCuts(const std::vector<double>& correlation, double threshold,
                                        int min_scene_len);
std::vector<std::int64_t> DissolveCuts(const std::vector<double>& long_correlation, int long_window,
                                       double threshold, double steady, int min_scene_len);
// Dissolves as linear blends (signals blend_changed / blend_unexplained,
// entry t describing frame t - step): each run of at least min_run
// consecutive entries with changed >= min_changed and unexplained <=
// max_unexplained gives one cut at the frame its middle entry describes
// ((first + last) / 2 - step, rounded down, at least 1), if that is at least
// min_scene_len frames after the previous cut (or the first frame). Empty
// inputs give no cuts.
std::vector<std::int64_t> BlendCuts(const std::vector<double>& changed,
                                    const std::vector<double>& unexplained, int step,
                                    double min_changed, double max_unexplained, int min_run,
                                    int min_scene_len);
std::vector<std::int64_t> FadeCuts(const std::vector<double>& mean_intensity, double threshold,
                                   int min_scene_len, double fade_bias);
// The cut list of detector `name` (see boundary_detectors). Throws
// Error("bad_config") for an unknown name.
std::vector<std::int64_t> CutsOf(const std::string& name, const ShotSignals& s,
                                 const ShotBoundaryConfig& c);

// The rule of stage "shot_boundary" (see the file comment) on its
// measurements {"clip", "signals": the "shot_boundary" section of the
// analysis} (filters/verdict.h): pass, pass "trimmed" to the longest shot
// (summary["trim"]), or reject "shot_boundary". Throws
// Error("bad_measurements") when they lack a field it reads.
FilterVerdict DecideShots(const Json& measurements, const ShotBoundaryConfig& config);

}  // namespace doasido::filters
