#include "stages/stage_timeouts.h"

#include <algorithm>
#include <optional>

#include "core/config_check.h"
#include "core/error_codes.h"
#include "stages/stage_registry.h"

namespace doasido::stages {
namespace {

constexpr double kMaxTimeoutSeconds = 30 * 24 * 3600.0;

const StageEntry* Find(const std::string& stage) {
  const auto& table = StageTable();
  const auto it = std::find_if(table.begin(), table.end(),
                               [&](const StageEntry& e) { return e.name == stage; });
  return it == table.end() ? nullptr : &*it;
}

}  // namespace

void CheckStageTimeouts(const Json& config) {
  if (!config.is_object() || !config.contains(kTimeoutsSection)) return;
  const Json& section = config.at(kTimeoutsSection);
  if (!section.is_object()) {
    throw Error("bad_config", "[timeouts] is a table of stage = seconds",
                {.field = kTimeoutsSection});
  }
  for (const auto& [stage, value] : section.items()) {
    const std::string key = std::string(kTimeoutsSection) + "." + stage;
    if (stage != kNoProgressKey && Find(stage) == nullptr) {
      throw Error("bad_config",
                  "timeouts." + stage + " names no stage (nor is it " + kNoProgressKey + ")",
                  {.field = key});
    }
    if (!value.is_number()) {
      throw Error("bad_config", "timeouts." + stage + " is not a number of seconds: " + value.dump(),
                  {.field = key});
    }
    RequireInRange(kTimeoutsSection, stage, value.get<double>(), 1e-3, kMaxTimeoutSeconds);
  }
}

namespace {

std::optional<double> Configured(const Json& config, const std::string& key) {
  if (config.is_object() && config.contains(kTimeoutsSection) &&
      config.at(kTimeoutsSection).contains(key)) {
    return config.at(kTimeoutsSection).at(key).get<double>();
  }
  return std::nullopt;
}

}  // namespace

double StageTimeout(const Json& config, const std::string& stage) {
  if (const auto configured = Configured(config, stage)) return *configured;
  const StageEntry* entry = Find(stage);
  return entry ? entry->timeout_s : kMaxTimeoutSeconds;
}

const char* StageTimeoutCode(const std::string& stage) {
  const StageEntry* entry = Find(stage);
  return entry && !entry->deterministic ? kStageTimeoutTransient : kStageTimeout;
}

double NoProgressLimit(const Json& config) {
  return Configured(config, kNoProgressKey).value_or(kDefaultNoProgressSeconds);
}

}  // namespace doasido::stages
