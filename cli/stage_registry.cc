#include "cli/stage_registry.h"

#include "db/noop_stage.h"
#include "ingest/probe.h"
#include "retarget/kinematic_stage.h"

namespace doasido::cli {
namespace {

template <typename StageT, typename ConfigT>
std::function<std::unique_ptr<Stage>(const Json&)> Maker(const std::string& section) {
  return [section](const Json& config) -> std::unique_ptr<Stage> {
    ConfigT c;
    ReadSection(config, section, c);
    return std::make_unique<StageT>(c);
  };
}

}  // namespace

const std::vector<StageEntry>& StageTable() {
  static const std::vector<StageEntry> kTable = {
      {"probe", "size, fps, frame count, rotation and codec; rejects spans outside the video",
       true, Maker<ingest::ProbeStage, ingest::ProbeConfig>("probe")},
      {"retarget-kinematic",
       "fingertip retargeting of the clip bundle's right hand onto a robot hand (MuJoCo)", false,
       Maker<retarget::KinematicStage, retarget::KinematicStageConfig>("retarget_kinematic")},
      {"noop", "does nothing for work_ms milliseconds (queue diagnostics)", false,
       Maker<NoopStage, NoopConfig>("noop")},
  };
  return kTable;
}

std::unique_ptr<Stage> MakeStage(const std::string& name, const Json& config) {
  std::string known;
  for (const auto& entry : StageTable()) {
    if (entry.name == name) return entry.make(config);
    known += (known.empty() ? "" : ", ") + entry.name;
  }
  throw Error("unknown_stage", "no stage '" + name + "' (known: " + known + ")",
              {.field = "stage"});
}

std::vector<std::string> DefaultPipeline() {
  std::vector<std::string> names;
  for (const auto& entry : StageTable()) {
    if (entry.in_default_pipeline) names.push_back(entry.name);
  }
  return names;
}

}  // namespace doasido::cli
