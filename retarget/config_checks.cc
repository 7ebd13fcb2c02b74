#include "retarget/config_checks.h"

#include <numbers>

#include "core/config_check.h"
#include "robot/embodiment.h"

namespace doasido::retarget {

void CheckConfig(const KinematicConfig& c, const std::string& section) {
  RequireInRange(section, "restarts", c.restarts, 0, 1000);
  RequireInRange(section, "jump_distance", c.jump_distance, 0, 10);  // m; 0: every frame restarts
  RequireInRange(section, "max_iterations", c.max_iterations, 1, 1e5);
  RequireInRange(section, "tolerance", c.tolerance, 1e-16, 1e-2);
  RequireInRange(section, "sigma", c.sigma, 1e-6, 1);  // m
  RequireInRange(section, "smooth_weight", c.smooth_weight, 0, 1e6);
  RequireInRange(section, "scale", c.scale, 0, 10);  // 0 adapts; robot hands are 0.5-3x
  RequireInRange(section, "wrist_noise_rad", c.wrist_noise_rad, 0, std::numbers::pi);
  RequireInRange(section, "wrist_noise_m", c.wrist_noise_m, 0, 1);
  RequireInRange(section, "robust_loss_scale", c.robust_loss_scale, 0, 1e3);
  RequireInRange(section, "contact_weight", c.contact_weight, 0, 1e6);
  RequireInRange(section, "contact_epsilon", c.contact_epsilon, 0, 0.2);  // m
  RequireInRange(section, "contact_depth", c.contact_depth, 0, 0.02);     // m
}

void CheckConfig(const DecompositionConfig& c, const std::string& section) {
  RequireOneOf(section, "method", c.method, {"split", "hacd"});
  RequireInRange(section, "max_depth", c.max_depth, 0, 20);
  RequireInRange(section, "concavity", c.concavity, 0, 1);
  RequireInRange(section, "min_hulls", c.min_hulls, 1, 1e4);
  RequireInRange(section, "max_vertices_per_hull", c.max_vertices_per_hull, 4, 1e4);
  RequireInRange(section, "max_input_triangles", c.max_input_triangles, 4, 1e7);
  RequireInRange(section, "max_hulls", c.max_hulls, 1, 1e5);
  RequireInRange(section, "min_solidity", c.min_solidity, 0, 1);
}

void CheckConfig(const SceneConfig& c, const std::string& section) {
  RequireInRange(section, "density", c.density, 1, 1e5);  // kg/m^3: foam to osmium
  RequireInRange(section, "dilation", c.dilation, 0, 0.1);
  RequireInRange(section, "plate_thickness", c.plate_thickness, 0, 0.1);
  RequireInRange(section, "settle_seconds", c.settle_seconds, 0, 60);
  RequireInRange(section, "timestep", c.timestep, 1e-5, 0.1);
  for (double f : c.friction) RequireInRange(section, "friction", f, 0, 10);
  // MuJoCo: positive solref is (timeconst, dampratio), negative is (-stiffness, -damping).
  for (double r : c.solref) RequireInRange(section, "solref", r, -1e9, 1e9);
  for (double i : c.solimp) RequireInRange(section, "solimp", i, 0, 1);
  RequireOneOf(section, "condim", std::to_string(c.condim), {"1", "3", "4", "6"});
  CheckConfig(c.decomposition, section + ".decomposition");
}

void CheckHandName(const std::string& name, const std::string& robots_dir,
                   const std::string& section, const std::string& field) {
  if (name.empty()) return;
  try {
    FindEmbodiment(name, robots_dir.empty() ? DefaultRobotsDir() : robots_dir);
  } catch (const Error& e) {
    throw Error("bad_config", "no hand '" + name + "': " + e.message(),
                {.file = e.site().file, .field = section + "." + field});
  }
}

}  // namespace doasido::retarget
