// Logging goes through spdlog to stderr. Commands call InitLogging once with
// the verbosity the user asked for; library code just uses spdlog::info etc.
#pragma once

#include <string>

#include <spdlog/spdlog.h>

namespace doasido {

// level: "trace", "debug", "info", "warn", "error" or "off".
void InitLogging(const std::string& level = "info");

}  // namespace doasido
