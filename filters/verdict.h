// What the five verdict rules share: where the analysis stage keeps its
// measurements, the verdict a rule returns, and the helpers the rules read
// their input with.
//
// A rule's input is the verdict stage's measurements {"clip": {...},
// "signals": {...}, "shot": {...}}: "clip" and "signals" are copied from
// the analysis (VerdictInput); "shot" (present when the shot-boundary
// verdict came before) holds its boundaries and trim, so that the later
// filters judge only the shot that is kept. Its output (FilterVerdict)
// holds the same measurements plus the "summary" the rule derived with its
// thresholds. A rule reads "clip", "signals" and "shot" only, so a verdict
// can always be re-derived from the measurements stored with it (`doasido
// rethreshold`). The queue stages that run the rules are in
// stages/verdict_stages.h.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/error.h"
#include "core/records.h"

namespace doasido::filters {

// Name of the stage that decodes each clip once (filters/analyze.h).
inline constexpr const char* kAnalyzeStageName = "filters_analyze";
// Its section with the learned hand detector's samples and keypoints
// (filters/learned_hand_detector.h).
inline constexpr const char* kHandsMeasurement = "hands";
// Reason code of the verdicts that need detections (interaction,
// out_of_frame): flag, the clip has none to judge by.
inline constexpr const char* kReasonNoDetections = "no_detections";

// The analysis's section naming the sections it did not measure because a
// cheap verdict removed the clip before their measurement ran
// (filters/deferred_hand_models.h): {"stage": the verdict's stage,
// "reason": its reason code, "sections": [...], "measured_by":
// kAnalyzeStageName, the stage to run again for them}. A verdict stage
// whose section is among them records Verdict::kNotMeasured with reason
// "stage", never pass, reject or flag (NotMeasured below).
inline constexpr const char* kNotMeasuredKey = "not_measured";

// What a verdict rule decides: pass, reject or flag with a reason code, and
// the measurements it decided from with its "summary" added.
struct FilterVerdict {
  Verdict verdict = Verdict::kPass;
  std::string reason;  // machine-readable reason code, e.g. "camera_motion"
  Json measurements = Json::object();
};

// {"clip": analysis["clip"], "signals": analysis[section], "shot": ...}:
// the input of the rule of stage `section` from the analysis stage's
// measurements `analysis`, with the shot the shot-boundary verdict kept
// when its measurements `shot_verdict` are given; {"clip", "not_measured":
// analysis["not_measured"]} when the analysis names `section` among those
// it did not measure. Throws Error("missing_measurements") at `site` when
// `analysis` lacks "clip" or `section` otherwise.
Json VerdictInput(const Json& analysis, const std::string& section, const Json* shot_verdict,
                  const ErrorSite& site);

// The verdict of a stage on `input` (a rule's input or its stored
// measurements) when its measurement did not run: not_measured, the reason
// the stage of the verdict that made it unnecessary, the measurements
// `input` itself. nullopt when `input` holds a measurement to decide from.
std::optional<FilterVerdict> NotMeasured(const Json& input);

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

// A verdict other than pass, with its reason code.
inline void SetVerdict(FilterVerdict& result, Verdict verdict, std::string reason) {
  result.verdict = verdict;
  result.reason = std::move(reason);
}

// The per-frame integer array `key` of stored signals. Throws
// Error("bad_measurements") naming the key when it is missing.
std::vector<int> IntArray(const Json& signals, const char* key);

// Number read from a JSON object with a default.
double NumberOr(const Json& object, const std::string& key, double fallback);

}  // namespace doasido::filters
