#include "retarget/dynamic/sampler_ladder.h"

#include <cmath>

#include "robot/trajectory/format.h"

namespace doasido::retarget {

bool BetterTracking(const TrackingMetrics& a, const TrackingMetrics& b) {
  if (a.success != b.success) return a.success;
  const double ea = a.e_pos / kSuccessPosition + a.e_rot / kSuccessRotation;
  const double eb = b.e_pos / kSuccessPosition + b.e_rot / kSuccessRotation;
  if (std::isnan(eb)) return !std::isnan(ea);
  return ea < eb;
}

void WriteLadderMeasurements(const std::vector<RungOutcome>& rungs, int best_rung, Json& m) {
  m[kMeasurementRung] = best_rung >= 0 ? rungs[best_rung].name : "";
  m[kMeasurementRungsRun] = rungs.size();
  m[kMeasurementRungs] = Json::array();
  for (const RungOutcome& r : rungs) {
    m[kMeasurementRungs].push_back(r.name);
    m[RungMeasurementKey(r.name, kRungSeconds)] = r.seconds;
    m[RungMeasurementKey(r.name, kMetricPositionError)] = r.metrics.e_pos;
    m[RungMeasurementKey(r.name, kMetricRotationError)] = r.metrics.e_rot;
    m[RungMeasurementKey(r.name, kMetricSuccess)] = r.metrics.success;
  }
}

}  // namespace doasido::retarget
