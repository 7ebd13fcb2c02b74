// The config file reader (core/config.h: TOML through toml++, JSON with
// limits) and the shape check every stage section goes through
// (core/config_check.h), on arbitrary bytes. The first byte picks TOML or
// JSON. Only doasido::Error may come out.
#include <cstddef>
#include <cstdint>

#include "core/config.h"
#include "core/config_check.h"
#include "core/error.h"
#include "tests/fuzz/fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  const auto path = doasido::fuzz::WriteInput((data[0] & 1) ? "c.json" : "c.toml", text);
  // A stage section's defaults: numbers, a string, a flag and a nested table.
  static const doasido::Json kDefaults = {
      {"threshold", 0.5}, {"window", 8}, {"mode", "fast"}, {"enabled", true},
      {"thumbnail", {{"height", 120}, {"quality", 0.9}}}};
  try {
    const doasido::Json config = doasido::LoadConfigFile(path);
    if (config.is_object()) {
      for (const auto& [section, value] : config.items()) {
        doasido::RequireSameShape(section, kDefaults, value);
      }
    }
  } catch (const doasido::Error&) {
  }
  return 0;
}
