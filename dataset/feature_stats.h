// Per-dimension statistics of a feature, as LeRobot's meta/stats.json and
// the stats/<feature>/<stat> columns of its episodes table hold them.
#pragma once

#include <cstdint>
#include <vector>

#include "core/config.h"

namespace doasido::dataset {

inline constexpr const char* kStatNames[] = {"min", "max",  "mean", "std", "count",
                                             "q01", "q10", "q50", "q90", "q99"};

struct FeatureStats {
  std::vector<double> min, max, mean, std;  // std: population (numpy's ddof=0)
  std::int64_t count = 0;                   // rows
  // Quantiles by linear interpolation between order statistics (numpy's default).
  std::vector<double> q01, q10, q50, q90, q99;
};

// Statistics over `rows` (each of the same length; at least one row).
FeatureStats ComputeStats(const std::vector<std::vector<double>>& rows);
// {"min": [...], ..., "count": [n], "q01": [...], ...}
Json ToJson(const FeatureStats& s);
// The values as a float32 column stores them.
std::vector<std::vector<double>> AsFloat32(const std::vector<std::vector<double>>& rows);

}  // namespace doasido::dataset
