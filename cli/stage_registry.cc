#include "cli/stage_registry.h"

#include "db/noop_stage.h"
#include "filters/activity.h"
#include "filters/analyze_stage.h"
#include "filters/camera_motion.h"
#include "filters/interaction.h"
#include "filters/out_of_frame.h"
#include "filters/shot_boundary.h"
#include "ingest/download_stage.h"
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
      {ingest::kDownloadStageName,
       "fetches clips listed by URL into the media folder (libcurl, or a yt-dlp command "
       "template for sites); local videos pass at once",
       true, Maker<ingest::DownloadStage, ingest::DownloadConfig>(ingest::kDownloadStageName)},
      {"probe", "size, fps, frame count, rotation and codec; rejects spans outside the video",
       true, Maker<ingest::ProbeStage, ingest::ProbeConfig>("probe")},
      {"hand_object_detector",
       "runs an external hand-object detector command and stores its 100DOH-format boxes", false,
       Maker<filters::ExternalDetectorStage, filters::ExternalDetectorConfig>(
           "hand_object_detector")},
      {"filters_analyze",
       "decodes the clip once at ~256 px and records every filter's per-frame signals", true,
       Maker<filters::AnalyzeStage, filters::AnalyzeConfig>("filters_analyze")},
      {"shot_boundary", "trims a clip to its longest shot, or rejects it across a cut", true,
       Maker<filters::ShotBoundaryStage, filters::ShotBoundaryConfig>("shot_boundary"), true},
      {"interaction", "rejects clips without hand-object contact", true,
       Maker<filters::InteractionStage, filters::InteractionConfig>("interaction"), true},
      {"out_of_frame", "rejects clips whose hand or touched object leaves the frame", true,
       Maker<filters::OutOfFrameStage, filters::OutOfFrameConfig>("out_of_frame"), true},
      {"activity", "rejects clips with no motion in the hand region", true,
       Maker<filters::ActivityStage, filters::ActivityConfig>("activity"), true},
      {"camera_motion", "rejects (or flags) clips whose camera pans, shakes or zooms", true,
       Maker<filters::CameraMotionStage, filters::CameraMotionConfig>("camera_motion"), true},
      {retarget::kKinematicStageName,
       "fingertip retargeting of the clip bundle's right hand onto a robot hand (MuJoCo)", false,
       Maker<retarget::KinematicStage, retarget::KinematicStageConfig>(retarget::kKinematicStageName)},
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
