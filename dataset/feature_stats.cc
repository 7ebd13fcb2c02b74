#include "dataset/feature_stats.h"

#include <algorithm>
#include <cmath>

namespace doasido::dataset {
namespace {

double Quantile(const std::vector<double>& sorted, double q) {
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - static_cast<double>(lo));
}

}  // namespace

FeatureStats ComputeStats(const std::vector<std::vector<double>>& rows) {
  FeatureStats s;
  s.count = static_cast<std::int64_t>(rows.size());
  if (rows.empty()) return s;
  const size_t dims = rows[0].size();
  std::vector<double> column(rows.size());
  for (size_t d = 0; d < dims; ++d) {
    double sum = 0;
    for (size_t r = 0; r < rows.size(); ++r) sum += column[r] = rows[r][d];
    const double mean = sum / static_cast<double>(rows.size());
    double var = 0;
    for (double v : column) var += (v - mean) * (v - mean);
    std::sort(column.begin(), column.end());
    s.min.push_back(column.front());
    s.max.push_back(column.back());
    s.mean.push_back(mean);
    s.std.push_back(std::sqrt(var / static_cast<double>(rows.size())));
    s.q01.push_back(Quantile(column, 0.01));
    s.q10.push_back(Quantile(column, 0.10));
    s.q50.push_back(Quantile(column, 0.50));
    s.q90.push_back(Quantile(column, 0.90));
    s.q99.push_back(Quantile(column, 0.99));
  }
  return s;
}

Json ToJson(const FeatureStats& s) {
  return {{"min", s.min},   {"max", s.max},   {"mean", s.mean}, {"std", s.std},
          {"count", {s.count}}, {"q01", s.q01}, {"q10", s.q10},   {"q50", s.q50},
          {"q90", s.q90},   {"q99", s.q99}};
}

std::vector<std::vector<double>> AsFloat32(const std::vector<std::vector<double>>& rows) {
  std::vector<std::vector<double>> out = rows;
  for (auto& r : out) {
    for (double& v : r) v = static_cast<double>(static_cast<float>(v));
  }
  return out;
}

}  // namespace doasido::dataset
