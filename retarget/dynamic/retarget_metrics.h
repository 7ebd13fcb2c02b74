// Object tracking metrics of a retargeted trajectory (SPIDER; seed section 4):
// E_pos = mean over frames of |t_sim - t_ref| (m), E_rot = mean over frames
// of the angle of R_ref^T R_sim (rad); a trajectory succeeds when
// E_pos < 0.1 m and E_rot < 0.5 rad.
#pragma once

#include <vector>

#include "core/geometry.h"

namespace doasido::retarget {

inline constexpr double kSuccessPosition = 0.10;  // m
inline constexpr double kSuccessRotation = 0.5;   // rad

struct TrackingMetrics {
  double e_pos = 0;
  double e_rot = 0;
  bool success = false;
  int frames = 0;  // frames averaged
};

// Averages over frames t with `valid` empty or valid[t]; `simulated` and
// `reference` have the same length. No frame: e_pos = e_rot = NaN, failure.
TrackingMetrics ObjectTrackingMetrics(const std::vector<Pose>& simulated,
                                      const std::vector<Pose>& reference,
                                      const std::vector<bool>& valid = {});

}  // namespace doasido::retarget
