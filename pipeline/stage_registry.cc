#include "pipeline/stage_registry.h"

#include <algorithm>

#include "core/config_check.h"
#include "filters/activity.h"
#include "filters/analyze_stage.h"
#include "filters/camera_motion.h"
#include "filters/interaction.h"
#include "filters/out_of_frame.h"
#include "filters/shot_boundary.h"
#include "ingest/download_stage.h"
#include "video/probe.h"
#include "pipeline/noop_stage.h"
#include "recon/bundle_stage.h"
#include "recon/recon_stage.h"
#include "retarget/dynamic_stage.h"
#include "retarget/kinematic_stage.h"

namespace doasido::pipeline {
namespace {

// The table entry of a stage `StageT` configured by `ConfigT` from section
// `name`.
template <typename StageT, typename ConfigT>
StageEntry Entry(const std::string& name, std::string summary, bool in_default_pipeline,
                 bool decides_from_measurements = false) {
  static_assert(HasConfigCheck<ConfigT>, "every stage config states its valid ranges");
  return {.name = name,
          .summary = std::move(summary),
          .in_default_pipeline = in_default_pipeline,
          .make = [name](const Json& config) -> std::unique_ptr<Stage> {
            ConfigT c;
            ReadCheckedSection(config, name, c);
            return std::make_unique<StageT>(c);
          },
          .check =
              [name](const Json& config) {
                ConfigT c;
                ReadCheckedSection(config, name, c);
              },
          .decides_from_measurements = decides_from_measurements};
}

}  // namespace

const std::vector<StageEntry>& StageTable() {
  using namespace filters;
  static const std::vector<StageEntry> kTable = {
      Entry<ingest::DownloadStage, ingest::DownloadConfig>(
          ingest::kDownloadStageName,
          "fetches clips listed by URL into the media folder (libcurl, or a yt-dlp command "
          "template for sites); local videos pass at once",
          true),
      Entry<video::ProbeStage, video::ProbeConfig>(
          video::kProbeStageName,
          "size, fps, frame count, rotation and codec; rejects spans outside the video", true),
      Entry<ExternalDetectorStage, ExternalDetectorConfig>(
          kExternalDetectorStageName,
          "runs an external hand-object detector command and stores its 100DOH-format boxes",
          false),
      Entry<AnalyzeStage, AnalyzeConfig>(
          kAnalyzeStageName,
          "decodes the clip once at ~256 px and records every filter's per-frame signals", true),
      Entry<ShotBoundaryStage, ShotBoundaryConfig>(
          kShotBoundaryStageName, "trims a clip to its longest shot, or rejects it across a cut",
          true, true),
      Entry<InteractionStage, InteractionConfig>(
          kInteractionStageName, "rejects clips without hand-object contact", true, true),
      Entry<OutOfFrameStage, OutOfFrameConfig>(
          kOutOfFrameStageName, "rejects clips whose hand or touched object leaves the frame",
          true, true),
      Entry<ActivityStage, ActivityConfig>(
          kActivityStageName, "rejects clips with no motion in the hand region", true, true),
      Entry<CameraMotionStage, CameraMotionConfig>(
          kCameraMotionStageName, "rejects (or flags) clips whose camera pans, shakes or zooms",
          true, true),
      Entry<recon::BundleStage, recon::BundleStageConfig>(
          recon::kBundleStageName,
          "runs the model command that writes the clip bundle (or checks the bundle the list "
          "names)",
          false),
      Entry<recon::ReconStage, recon::ReconStageConfig>(
          recon::kReconStageName,
          "aligns hand and object to one metric scale, gravity-aligns: the 4D reconstruction",
          false),
      Entry<retarget::KinematicStage, retarget::KinematicStageConfig>(
          retarget::kKinematicStageName,
          "fingertip retargeting of the reconstructed right hand onto a robot hand (MuJoCo)",
          false),
      Entry<retarget::DynamicRetargetStage, retarget::DynamicRetargetConfig>(
          retarget::kRetargetStageName,
          "dynamics-aware retargeting of the recon artifact: annealed sampling in MuJoCo (seed "
          "3.2)",
          false),
      Entry<NoopStage, NoopConfig>(kNoopStageName,
                                   "does nothing for work_ms milliseconds (queue diagnostics)",
                                   false),
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

std::set<std::string> FlagContinuingStages(const std::vector<std::string>& pipeline) {
  std::set<std::string> out;
  for (size_t i = 0; i + 1 < pipeline.size(); ++i) {
    for (const auto& entry : StageTable()) {
      if (entry.name == pipeline[i + 1] && entry.decides_from_measurements) {
        out.insert(pipeline[i]);
      }
    }
  }
  return out;
}

void CheckStageConfig(const Json& config, const std::vector<std::string>& other_sections) {
  if (!config.is_object()) throw Error("bad_config", "the configuration is not a table");
  std::vector<std::string> known = other_sections;
  for (const auto& entry : StageTable()) known.push_back(entry.name);
  for (const auto& [section, value] : config.items()) {
    if (std::find(known.begin(), known.end(), section) != known.end()) continue;
    std::string list;
    for (const auto& name : known) list += (list.empty() ? "" : ", ") + name;
    throw Error("bad_config", "unknown section [" + section + "] (known: " + list + ")",
                {.field = section});
  }
  for (const auto& entry : StageTable()) entry.check(config);
}

}  // namespace doasido::pipeline
