// Configuration checked when it is loaded. A config struct states its valid
// ranges in a free function found by argument-dependent lookup,
//   void CheckConfig(const MyStageConfig& c, const std::string& section);
// that throws Error("bad_config") for a value that cannot be right (use
// RequireInRange), so a bad file is refused before any clip runs instead of
// failing every clip after its retries.
#pragma once

#include <string>
#include <vector>

#include "core/config.h"
#include "core/error.h"

namespace doasido {

// Throws Error("bad_config") naming `section.key`, the value and the allowed
// range unless lo <= value <= hi (NaN is never in range).
void RequireInRange(const std::string& section, const std::string& key, double value, double lo,
                    double hi);

// Throws Error("bad_config") naming `section.key` and the choices unless
// `value` is one of `choices`.
void RequireOneOf(const std::string& section, const std::string& key, const std::string& value,
                  const std::vector<std::string>& choices);

template <typename T>
concept HasConfigCheck = requires(const T& c, const std::string& s) { CheckConfig(c, s); };

// Throws Error("bad_config") naming `section.key` (nested keys joined by
// dots) for a value in `given` whose JSON type differs from the default's
// (a string for a number, a fraction for an integer or one past int's
// range written as a float, a negative number for an unsigned one) or for a
// nested key the default lacks. `defaults` is the
// config struct serialised with its defaults.
void RequireSameShape(const std::string& section, const Json& defaults, const Json& given);

// ReadSection (core/config.h) followed by the struct's range check, which
// runs also when the section is absent (defaults must be valid too).
template <typename T>
  requires HasConfigCheck<T>
void ReadCheckedSection(const Json& config, const std::string& section, T& out) {
  if (config.is_object() && config.contains(section)) {
    RequireSameShape(section, Json(out), config.at(section));
  }
  ReadSection(config, section, out);
  CheckConfig(out, section);
}

}  // namespace doasido
