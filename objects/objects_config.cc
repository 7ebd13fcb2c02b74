#include "objects/objects_config.h"

#include "core/config_check.h"
#include "objects/box_keypoints_config.h"

namespace doasido::objects {

void CheckConfig(const ObjectsConfig& c, const std::string& section) {
  RequireInRange(section, "min_score", c.min_score, 0, 1);
  RequireInRange(section, "min_track_frames", c.min_track_frames, 1, 100000);
  RequireInRange(section, "max_gap_frames", c.max_gap_frames, 0, 300);
  RequireInRange(section, "degenerate_ratio", c.degenerate_ratio, 0, 1);
  RequireInRange(section, "min_contact_frames", c.min_contact_frames, 1, 100000);
  RequireInRange(section, "fingertip_offset_m", c.fingertip_offset_m, 0, 0.05);
  RequireInRange(section, "contact_robust_m", c.contact_robust_m, 1e-4, 1);
  RequireInRange(section, "max_contact_residual_m", c.max_contact_residual_m, 1e-4, 1);
  RequireInRange(section + ".carry", "hold_distance_m", c.carry.hold_distance_m, 0, 1);
  RequireInRange(section + ".carry", "max_deviation_m", c.carry.max_deviation_m, 1e-3, 10);
  RequireInRange(section + ".carry", "max_frames", c.carry.max_frames, 0, 100000);
  RequireInRange(section, "cylinder_segments", c.cylinder_segments, 8, 1024);
  const std::string f = section + ".fit";
  RequireInRange(f, "reprojection_sigma", c.fit.reprojection_sigma, 1e-4, 1);
  RequireInRange(f, "huber", c.fit.huber, 0.1, 100);
  RequireInRange(f, "acceleration_sigma_ms2", c.fit.acceleration_sigma_ms2, 1e-3, 1e4);
  RequireInRange(f, "angular_acceleration_sigma", c.fit.angular_acceleration_sigma, 1e-3, 1e6);
  RequireInRange(f, "max_iterations", c.fit.max_iterations, 1, 10000);
  CheckConfig(c.models, section + ".models");
}

}  // namespace doasido::objects
