// Valid ranges of the retargeting configs, checked when a configuration is
// loaded (core/config_check.h); each throws Error("bad_config") naming
// section.key, the value and the allowed range.
#pragma once

#include <string>

#include "retarget/kinematic/kinematic_retarget.h"
#include "retarget/scene/convex_decomposition.h"
#include "retarget/scene/scene_builder.h"

namespace doasido::retarget {

void CheckConfig(const KinematicConfig& c, const std::string& section);
void CheckConfig(const DecompositionConfig& c, const std::string& section);
void CheckConfig(const SceneConfig& c, const std::string& section);
// Each non-empty name must resolve to a hand description (FindEmbodiment
// in `robots_dir`, "" = DefaultRobotsDir()); else Error("bad_config")
// naming section.<field>, so a misspelt hand stops the load, not every
// clip's run.
void CheckHandName(const std::string& name, const std::string& robots_dir,
                   const std::string& section, const std::string& field);

}  // namespace doasido::retarget
