// Activity: is anything moving where the hands are?
//
// Signals (analysis pass), per frame against the previous frame, on the gray
// analysis image: the region is the union of the frame's hand boxes grown by
// box_margin (the whole frame when no hand box is known); `energy` is the
// mean |difference| over the region in gray levels and `moving` the fraction
// of region pixels that changed by more than pixel_threshold levels. Frame 0
// has no predecessor and records 0. `hands_region` is 1 where the region came
// from hand boxes.
//
// Decision (DecideActivity): a frame is active when moving >=
// min_moving_fraction; the clip is active when at least min_active_fraction
// of its frames (of the kept shot, when the shot filter trimmed it) are.
// Otherwise reject "no_activity".
//
// What it does not do: it does not compensate camera motion (a static scene
// filmed by a moving camera counts as active; the camera-motion filter is the
// one that rejects it).
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
inline constexpr const char* kActivityStageName = "activity";
// Reason code: reject, too little motion in the hand region.
inline constexpr const char* kReasonNoActivity = "no_activity";

struct ActivitySignalConfig {
  double box_margin = 0.25;  // grow hand boxes by this fraction per side
  int pixel_threshold = 15;  // gray levels
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ActivitySignalConfig, box_margin, pixel_threshold)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const ActivitySignalConfig& c, const std::string& section);

struct ActivitySignals {
  std::vector<double> energy;
  std::vector<double> moving;
  std::vector<int> hands_region;
};
Json ToJson(const ActivitySignals& s);
ActivitySignals ActivitySignalsFromJson(const Json& j);  // throws Error("bad_measurements")

// The fraction of pixels where the gray images `a` and `b` (same size)
// differ by more than config.pixel_threshold levels, over the union of
// `hands` grown by config.box_margin per side (the whole frame when there
// are none): the `moving` signal above between any two frames. The learned
// detector's motion-following sampling (filters/learned_hand_detector.h)
// measures it between a sample and the last one the models saw.
double MovingFraction(const cv::Mat& a, const cv::Mat& b, const std::vector<cv::Rect2d>& hands,
                      const ActivitySignalConfig& config);

class ActivityExtractor : public FrameConsumer {
 public:
  explicit ActivityExtractor(ActivitySignalConfig config = {}) : config_(config) {}
  void Consume(FrameContext& context) override;
  const ActivitySignals& signals() const { return signals_; }

 private:
  ActivitySignalConfig config_;
  ActivitySignals signals_;
  cv::Mat prev_gray_, diff_;
};

struct ActivityConfig {
  double min_moving_fraction = 0.01;
  double min_active_fraction = 0.10;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ActivityConfig, min_moving_fraction,
                                                min_active_fraction)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const ActivityConfig& c, const std::string& section);

// Fraction of the frames first..last (inclusive positions; frame 0, which
// has no predecessor, never counts) whose moving fraction is >= `min_moving`.
double ActiveFraction(const ActivitySignals& s, double min_moving, std::int64_t first,
                      std::int64_t last);

// The rule of stage "activity" (see the file comment) on its
// measurements {"clip", "signals": the "activity" section of the analysis,
// "shot"} (filters/verdict.h): reject "no_activity", else pass. Throws
// Error("bad_measurements") when they lack a field it reads.
FilterVerdict DecideActivity(const Json& measurements, const ActivityConfig& config);

}  // namespace doasido::filters
