#include "hands/hands_config.h"

#include "core/config_check.h"
#include "filters/hand_models.h"

namespace doasido::hands {

void CheckConfig(const HandsConfig& c, const std::string& section) {
  RequireInRange(section, "default_fov_deg", c.default_fov_deg, 10, 170);
  RequireInRange(section, "max_hands", c.max_hands, 1, 2);
  RequireInRange(section, "max_side", c.max_side, 128, 4096);
  RequireOneOf(section, "backend", c.backend, {"native", "wasm"});
  RequireOneOf(section, "models", c.models,
               {filters::kModelsFull, filters::kModelsLite, filters::kModelsLiteLandmark});
  RequireInRange(section, "palm_every", c.palm_every, 1, 1000);
  RequireInRange(section, "wide_search_every", c.wide_search_every, 0, 100000);
  RequireInRange(section, "lost_wide_search", c.lost_wide_search, 0, 100000);
  const std::string t = section + ".tracker";
  RequireInRange(t, "min_score", c.tracker.min_score, 0, 1);
  RequireInRange(t, "max_gap_frames", c.tracker.max_gap_frames, 0, 300);
  RequireInRange(t, "max_jump", c.tracker.max_jump, 0.01, 100);
  RequireInRange(t, "min_track_frames", c.tracker.min_track_frames, 1, 100000);
  RequireInRange(t, "duplicate_distance", c.tracker.duplicate_distance, 0, 10);
  RequireInRange(t, "min_arrangement_lean", c.tracker.min_arrangement_lean, 0, 1);
  const std::string f = section + ".fit";
  RequireInRange(f, "reprojection_sigma", c.fit.reprojection_sigma, 1e-4, 1);
  RequireInRange(f, "huber", c.fit.huber, 0.1, 100);
  RequireInRange(f, "bone_sigma_m", c.fit.bone_sigma_m, 1e-5, 1);
  RequireInRange(f, "shape_sigma_m", c.fit.shape_sigma_m, 1e-5, 1);
  RequireInRange(f, "acceleration_sigma_ms2", c.fit.acceleration_sigma_ms2, 1e-3, 1e4);
  RequireInRange(f, "max_iterations", c.fit.max_iterations, 1, 10000);
  RequireInRange(f, "max_pnp_turn_deg", c.fit.max_pnp_turn_deg, 1, 180);
  RequireInRange(f, "max_untrusted_run", c.fit.max_untrusted_run, 0, 300);
  RequireInRange(f, "max_wrist_speed_m_s", c.fit.max_wrist_speed_m_s, 0.1, 100);
  RequireInRange(f, "max_wrist_turn_deg_s", c.fit.max_wrist_turn_deg_s, 10, 100000);
  RequireOneOf(f, "size_prior", c.fit.size_prior, {"adult", "model"});
  RequireInRange(f, "hand_length_m", c.fit.hand_length_m, 0.08, 0.3);
  RequireInRange(f, "hand_length_sigma", c.fit.hand_length_sigma, 0.005, 1);
}

}  // namespace doasido::hands
