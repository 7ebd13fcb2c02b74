// Configuration checked when it is loaded. A config struct states its valid
// ranges in a free function found by argument-dependent lookup,
//   void CheckConfig(const MyStageConfig& c, const std::string& section);
// that throws Error("bad_config") for a value that cannot be right (use
// RequireInRange), so a bad file is refused before any clip runs instead of
// failing every clip after its retries.
#pragma once

#include <string>

#include "core/error.h"

namespace doasido {

// Throws Error("bad_config") naming `section.key`, the value and the allowed
// range unless lo <= value <= hi (NaN is never in range).
void RequireInRange(const std::string& section, const std::string& key, double value, double lo,
                    double hi);

template <typename T>
concept HasConfigCheck = requires(const T& c, const std::string& s) { CheckConfig(c, s); };

}  // namespace doasido
