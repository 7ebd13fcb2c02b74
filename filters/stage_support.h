// What the four verdict stages share: where the analysis stage keeps its
// measurements and how a verdict stage copies the part it decides from.
//
// Measurements of a verdict stage are {"clip": {...}, "signals": {...},
// "shot": {...}, "summary": {...}}: "clip" and "signals" are copied from the
// analysis stage; "shot" (present when the shot-boundary stage ran before)
// holds its boundaries and trim, so that the later filters judge only the
// shot that is kept; "summary" is what the stage derived with its
// thresholds. Redecide reads "clip", "signals" and "shot" only, so a verdict
// can always be re-derived from the stage's own measurements.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "db/stage.h"

namespace doasido::filters {

// Name of the stage that decodes each clip once (filters/analyze_stage.h).
inline constexpr const char* kAnalyzeStageName = "filters_analyze";
// Its section with the learned hand detector's samples and keypoints
// (filters/learned_hand_detector.h).
inline constexpr const char* kHandsMeasurement = "hands";
// Reason code of the verdicts that need detections (interaction,
// out_of_frame): flag, the clip has none to judge by.
inline constexpr const char* kReasonNoDetections = "no_detections";

// {"clip": analysis["clip"], "signals": analysis[section], "shot": ...} from
// the analysis stage's measurements in `context` (and the shot-boundary
// stage's, when present). Throws Error("missing_measurements") naming the
// clip when the analysis stage has not run or lacks `section`.
Json CopyAnalysis(const ClipContext& context, const std::string& section);

// The frames a verdict judges, as 0-based positions in the analysed span:
// the shot-boundary trim when there is one, else every frame; `boundaries`
// are the shot boundaries (positions of first frames of new shots).
struct ShotSpan {
  std::int64_t first = 0;  // inclusive
  std::int64_t last = -1;  // inclusive
  std::vector<std::int64_t> boundaries;
  bool Contains(std::int64_t i) const { return i >= first && i <= last; }
};
ShotSpan SpanOf(const Json& measurements, std::int64_t frames);

// Checks that `measurements` has "clip" and "signals" objects. Throws
// Error("bad_measurements") naming `stage` otherwise.
void RequireAnalysis(const Json& measurements, const std::string& stage);

// One thresholded score of a verdict, as stored in summary["scores"] for
// reports and the review page: {"name", "value", "rejects": "above" |
// "below", "reject": threshold, "flag": threshold (only when given)}.
// "above" rejects value >= reject; "below" rejects value < reject.
Json ScoreEntry(const std::string& name, double value, bool rejects_above, double reject,
                double flag = std::numeric_limits<double>::quiet_NaN());

// A verdict stage that decides from the analysis stage's measurements only
// (never decodes): Run copies the stage's section of them, with the kept
// shot, and applies `rule`; Redecide applies `rule` to stored measurements,
// so `doasido rethreshold` re-derives the verdict without the video. The
// stage's name is also its section in the analysis measurements.
template <typename Config>
class MeasuredVerdictStage : public Stage {
 public:
  using Rule = StageResult (*)(const Json& measurements, const Config& config);
  MeasuredVerdictStage(std::string name, Config config, Rule rule)
      : name_(std::move(name)), config_(std::move(config)), rule_(rule) {}
  std::string Name() const override { return name_; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override {
    return rule_(CopyAnalysis(context, name_), config_);
  }
  std::optional<StageResult> Redecide(const Json& measurements) const override {
    return rule_(measurements, config_);
  }

 private:
  std::string name_;
  Config config_;
  Rule rule_;
};

// A verdict other than pass, with its reason code.
inline void SetVerdict(StageResult& result, Verdict verdict, std::string reason) {
  result.verdict = verdict;
  result.reason = std::move(reason);
}

// The per-frame integer array `key` of stored signals. Throws
// Error("bad_measurements") naming the key when it is missing.
std::vector<int> IntArray(const Json& signals, const char* key);

// Number read from a JSON object with a default.
double NumberOr(const Json& object, const std::string& key, double fallback);

}  // namespace doasido::filters
