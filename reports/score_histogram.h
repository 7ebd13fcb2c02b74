// Per filter score distributions: every entry of a verdict stage's
// `summary.scores` ({"name", "value", "rejects": "above"|"below", "reject",
// optional "flag"}) gathered across clips, counted on each side of its
// thresholds and binned for a histogram.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/records.h"

namespace doasido::reports {

struct ScoreDistribution {
  std::string stage;
  std::string name;
  std::string rejects = "above";  // "above": high values reject; "below": low values
  // Thresholds drawn on the histogram: the most common ones across clips.
  double reject = 0;  // NaN when the entries carry no threshold
  std::optional<double> flag;
  bool thresholds_vary = false;  // clips were decided with different thresholds
  std::vector<double> values;    // finite values, in clip order
  std::int64_t non_finite = 0;   // NaN or infinite values (not binned)
  // Clips on each side, each judged against its own stored thresholds:
  // "above" rejects value >= reject and flags flag <= value < reject;
  // "below" rejects value < reject and flags reject <= value < flag.
  std::int64_t reject_side = 0;
  std::int64_t flag_zone = 0;
  std::int64_t pass_side = 0;
  // Histogram: `bins.size()` equal bins over [lo, hi].
  double lo = 0, hi = 1;
  std::vector<std::int64_t> bins;
};

struct StageScores {
  std::string stage;
  std::int64_t measured = 0;     // clips with measurements of this stage
  std::int64_t with_scores = 0;  // of those, clips whose summary has scores
  std::vector<ScoreDistribution> scores;  // in order of first appearance
};

// Gathers summaries stage by stage; Finish bins them.
class ScoreCollector {
 public:
  // One clip's `summary` of `stage` (may be null or lack "scores"; entries
  // without a name or numeric value are skipped).
  void Add(const std::string& stage, const Json& summary);
  // Registers `stage` (so it appears, in order, even without measurements).
  void AddStage(const std::string& stage);
  // Distributions of every stage added, in the order stages were first
  // added, each binned into `bins` bins (>= 1).
  std::vector<StageScores> Finish(int bins) const;

 private:
  struct Accumulator {
    ScoreDistribution dist;
    // (reject, flag) -> clips; optional keeps NaN out of the ordering.
    std::map<std::pair<std::optional<double>, std::optional<double>>, std::int64_t>
        threshold_votes;
  };
  std::vector<std::string> stage_order_;
  std::map<std::string, StageScores> stages_;
  std::map<std::string, std::vector<std::string>> score_order_;
  std::map<std::pair<std::string, std::string>, Accumulator> acc_;
};

// Which side of its thresholds `value` falls on: "reject", "flag" or "pass".
std::string ScoreSide(double value, const std::string& rejects, double reject,
                      std::optional<double> flag);

// Bins `values` into `bins` equal bins over [lo, hi] (values outside are
// clamped into the end bins; the top edge belongs to the last bin).
std::vector<std::int64_t> BinValues(const std::vector<double>& values, double lo, double hi,
                                    int bins);

}  // namespace doasido::reports
