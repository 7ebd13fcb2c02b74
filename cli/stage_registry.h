// The table of queue stages the worker can run, in pipeline order. A new
// stage is one entry here; its module provides the Stage class and its
// config struct.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/config.h"
#include "db/stage.h"

namespace doasido::cli {

struct StageEntry {
  std::string name;
  std::string summary;
  bool in_default_pipeline;
  // Builds the stage from the whole config (the stage reads its section).
  std::function<std::unique_ptr<Stage>(const Json& config)> make;
  // Run() only reads stored measurements (no decoding), so `doasido
  // rethreshold` may re-decide and re-run it in process.
  bool decides_from_measurements = false;
};

const std::vector<StageEntry>& StageTable();
// Throws Error("unknown_stage") listing the known names.
std::unique_ptr<Stage> MakeStage(const std::string& name, const Json& config);
std::vector<std::string> DefaultPipeline();

}  // namespace doasido::cli
