#include "retarget/dynamic/retarget_metrics.h"

#include <cmath>

#include "core/error.h"

namespace doasido::retarget {

TrackingMetrics ObjectTrackingMetrics(const std::vector<Pose>& simulated,
                                      const std::vector<Pose>& reference,
                                      const std::vector<bool>& valid) {
  if (simulated.size() != reference.size()) {
    throw Error("bad_trajectory", "simulated and reference object poses differ in length");
  }
  TrackingMetrics m;
  for (size_t t = 0; t < simulated.size(); ++t) {
    if (!valid.empty() && !valid[t]) continue;
    m.e_pos += (simulated[t].t - reference[t].t).norm();
    m.e_rot += RotationAngle(reference[t].q, simulated[t].q);
    ++m.frames;
  }
  if (m.frames == 0) {
    m.e_pos = m.e_rot = std::nan("");
    return m;
  }
  m.e_pos /= m.frames;
  m.e_rot /= m.frames;
  m.success = m.e_pos < kSuccessPosition && m.e_rot < kSuccessRotation;
  return m;
}

}  // namespace doasido::retarget
