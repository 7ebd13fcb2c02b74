#include "reports/score_histogram.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace doasido::reports {

std::string ScoreSide(double value, const std::string& rejects, double reject,
                      std::optional<double> flag) {
  if (rejects == "below") {
    if (value < reject) return "reject";
    if (flag && value < *flag) return "flag";
    return "pass";
  }
  if (value >= reject) return "reject";
  if (flag && value >= *flag) return "flag";
  return "pass";
}

std::vector<std::int64_t> BinValues(const std::vector<double>& values, double lo, double hi,
                                    int bins) {
  bins = std::max(bins, 1);
  std::vector<std::int64_t> counts(bins, 0);
  const double width = (hi - lo) / bins;
  for (double v : values) {
    int b = width > 0 ? static_cast<int>(std::floor((v - lo) / width)) : 0;
    counts[std::clamp(b, 0, bins - 1)] += 1;
  }
  return counts;
}

void ScoreCollector::AddStage(const std::string& stage) {
  if (stages_.count(stage)) return;
  stage_order_.push_back(stage);
  stages_[stage].stage = stage;
}

void ScoreCollector::Add(const std::string& stage, const Json& summary) {
  AddStage(stage);
  StageScores& s = stages_[stage];
  ++s.measured;
  if (!summary.is_object() || !summary.contains("scores") || !summary["scores"].is_array()) {
    return;
  }
  ++s.with_scores;
  for (const Json& e : summary["scores"]) {
    if (!e.is_object() || !e.contains("name") || !e["name"].is_string()) continue;
    const std::string name = e["name"];
    // Non-finite numbers are stored as JSON null by nlohmann.
    double value = std::numeric_limits<double>::quiet_NaN();
    if (e.contains("value") && e["value"].is_number()) value = e["value"].get<double>();
    else if (!e.contains("value") || !e["value"].is_null()) continue;
    const double reject = e.contains("reject") && e["reject"].is_number()
                              ? e["reject"].get<double>()
                              : std::numeric_limits<double>::quiet_NaN();
    std::optional<double> flag;
    if (e.contains("flag") && e["flag"].is_number()) flag = e["flag"].get<double>();
    const std::string rejects = e.value("rejects", std::string("above"));

    auto key = std::make_pair(stage, name);
    auto [it, fresh] = acc_.try_emplace(key);
    Accumulator& a = it->second;
    if (fresh) {
      a.dist.stage = stage;
      a.dist.name = name;
      a.dist.rejects = rejects;
      score_order_[stage].push_back(name);
    }
    if (!std::isfinite(value)) {
      ++a.dist.non_finite;
      continue;
    }
    a.dist.values.push_back(value);
    a.threshold_votes[{std::isnan(reject) ? std::nullopt : std::optional<double>(reject), flag}] +=
        1;
    if (std::isnan(reject)) {
      ++a.dist.pass_side;
      continue;
    }
    const std::string side = ScoreSide(value, rejects, reject, flag);
    if (side == "reject") ++a.dist.reject_side;
    else if (side == "flag") ++a.dist.flag_zone;
    else ++a.dist.pass_side;
  }
}

std::vector<StageScores> ScoreCollector::Finish(int bins) const {
  std::vector<StageScores> out;
  for (const auto& stage : stage_order_) {
    StageScores s = stages_.at(stage);
    auto order = score_order_.find(stage);
    if (order != score_order_.end()) {
      for (const auto& name : order->second) {
        const Accumulator& a = acc_.at({stage, name});
        ScoreDistribution d = a.dist;
        std::int64_t best = -1;
        d.reject = std::numeric_limits<double>::quiet_NaN();
        for (const auto& [thresholds, votes] : a.threshold_votes) {
          if (votes > best) {
            best = votes;
            d.reject = thresholds.first.value_or(std::numeric_limits<double>::quiet_NaN());
            d.flag = thresholds.second;
          }
        }
        d.thresholds_vary = a.threshold_votes.size() > 1;
        double lo = std::numeric_limits<double>::infinity();
        double hi = -lo;
        for (double v : d.values) lo = std::min(lo, v), hi = std::max(hi, v);
        for (double t : {d.reject, d.flag.value_or(d.reject)}) {
          if (std::isfinite(t)) lo = std::min(lo, t), hi = std::max(hi, t);
        }
        if (!std::isfinite(lo)) lo = 0, hi = 1;
        if (hi - lo <= 0) lo -= 0.5, hi += 0.5;
        const double pad = 0.02 * (hi - lo);
        d.lo = lo - pad;
        d.hi = hi + pad;
        d.bins = BinValues(d.values, d.lo, d.hi, bins);
        s.scores.push_back(std::move(d));
      }
    }
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace doasido::reports
