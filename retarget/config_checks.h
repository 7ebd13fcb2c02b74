// Valid ranges of the retargeting configs, checked when a configuration is
// loaded (core/config_check.h); each throws Error("bad_config") naming
// section.key, the value and the allowed range.
#pragma once

#include <string>

#include "retarget/convex_decomposition.h"
#include "retarget/kinematic_retarget.h"
#include "retarget/scene_builder.h"

namespace doasido::retarget {

void CheckConfig(const KinematicConfig& c, const std::string& section);
void CheckConfig(const DecompositionConfig& c, const std::string& section);
void CheckConfig(const SceneConfig& c, const std::string& section);

}  // namespace doasido::retarget
