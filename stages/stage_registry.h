// The table of queue stages the worker can run, in pipeline order. A new
// stage is one entry here; its module provides the Stage class, its name
// constant and its config struct with CheckConfig (core/config_check.h).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/config.h"
#include "stages/stage.h"

namespace doasido::stages {

// A reason code a stage can give its verdict (the constants of its header),
// with the words a reviewer reads for it.
struct StageReason {
  std::string code;
  std::string label;
};

struct StageEntry {
  std::string name;  // the stage's name constant: also its config section
  std::string summary;
  // Every reason code the stage can give, its reject reason first (the one
  // a reviewer's rejection of a clip it flagged takes by default).
  std::vector<StageReason> reasons;
  bool in_filters_preset;  // one of the filtering job's stages (preset `filters`)
  // Builds the stage from the whole config (the stage reads and checks its
  // section).
  std::function<std::unique_ptr<Stage>(const Json& config)> make;
  // Reads and range-checks the stage's section without building the stage.
  std::function<void(const Json& config)> check;
  // Run() only reads stored measurements (no decoding), so `doasido
  // rethreshold` may re-decide and re-run it in process.
  bool decides_from_measurements = false;
  // Wall-clock limit of one run unless the config's [timeouts] says
  // otherwise (stages/stage_timeouts.h).
  double timeout_s = 600;
  // The same input gives the same outcome, so a timeout is not retried: it
  // fails as kStageTimeout, a permanent code, else as kStageTimeoutTransient
  // (StageTimeoutCode). The network stage is the one that is not.
  bool deterministic = true;
};

const std::vector<StageEntry>& StageTable();
// Throws Error("unknown_stage") listing the known names.
std::unique_ptr<Stage> MakeStage(const std::string& name, const Json& config);
// Named pipelines, words `doasido init --pipeline` expands: `default`, the
// whole chain (filters -> hands -> bundle -> recon -> retarget_kinematic ->
// retarget; what init and ingest give a database without a pipeline), and
// `filters`, the filtering job alone (download .. camera_motion: the
// report-only use).
inline constexpr const char* kPresetDefault = "default";
inline constexpr const char* kPresetFilters = "filters";
std::vector<std::string> DefaultPipeline();
std::vector<std::string> FiltersPipeline();
const std::map<std::string, std::vector<std::string>>& PipelinePresets();
// A --pipeline list with each preset word replaced by its stages. Throws
// Error("unknown_stage") for a name that is neither, Error("bad_pipeline")
// for a stage listed twice (naming the preset that holds it).
std::vector<std::string> ExpandPipeline(const std::vector<std::string>& words);
// Every reason code of the table, each once: the stages that decide from
// stored measurements (the filters) first, then the others, in table order
// (the review page's list).
std::vector<StageReason> StageReasons();
// For each stage that decides from stored measurements (the filters, whose
// flags a person reviews): its reject reason, by stage name.
std::map<std::string, std::string> ReviewDefaultReasons();
// The stages of `pipeline` where a flag lets the clip go on: those followed
// by a stage that decides from stored measurements (the filters), so that
// a flagged clip is judged by every filter before a person sees it.
std::set<std::string> FlagContinuingStages(const std::vector<std::string>& pipeline);

// Refuses a configuration before any clip runs: every section must name a
// stage of the table or one of `other_sections` (tables read outside the
// queue, e.g. "report"), and every stage's section must read with known
// keys, values of the right type and values in range. Throws
// Error("bad_config") naming section.key, the value and the allowed range.
void CheckStageConfig(const Json& config, const std::vector<std::string>& other_sections);

}  // namespace doasido::stages
