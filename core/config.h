// Configuration is data. Each stage has one plain struct whose member
// initialisers are the documented defaults (from the paper or the peer tool),
// made (de)serialisable with
//   NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(MyStageConfig, a, b, c)
// A config file (TOML or JSON) holds one table per stage:
//   [probe]
//   count_frames = true
// Keys that are missing keep their default; unknown keys are an error, so a
// typo never silently runs with the default.
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "core/error.h"

namespace doasido {

using Json = nlohmann::json;

// Reads a .toml or .json file into a JSON object. Throws Error
// ("bad_config") naming the file and, for TOML, the line.
Json LoadConfigFile(const std::filesystem::path& path);

// Stable 16-hex-digit hash of a JSON value (FNV-1a 64 over its canonical
// dump; object keys are sorted by nlohmann::json). Two parameter sets hash
// equal exactly when they serialise equal.
std::string ParamHash(const Json& params);

// Fills `out` from section `section` of `config` (which may be absent: then
// `out` keeps its defaults). Unknown keys throw Error("bad_config") naming
// the section and key.
template <typename T>
void ReadSection(const Json& config, const std::string& section, T& out) {
  if (!config.is_object() || !config.contains(section)) return;
  const Json& given = config.at(section);
  if (!given.is_object()) {
    throw Error("bad_config", "section is not a table", {.field = section});
  }
  Json defaults = out;
  for (const auto& [key, value] : given.items()) {
    if (!defaults.contains(key)) {
      throw Error("bad_config", "unknown key", {.field = section + "." + key});
    }
    (void)value;
  }
  defaults.merge_patch(given);
  try {
    out = defaults.get<T>();
  } catch (const nlohmann::json::exception& e) {
    throw Error("bad_config", std::string("wrong type: ") + e.what(), {.field = section});
  }
}

}  // namespace doasido
