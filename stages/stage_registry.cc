#include "stages/stage_registry.h"

#include <algorithm>
#include <type_traits>

#include "core/config_check.h"
#include "stages/analyze_stage.h"
#include "stages/bundle_stage.h"
#include "stages/detector_stage.h"
#include "stages/download_stage.h"
#include "stages/dynamic_stage.h"
#include "stages/hands_stage.h"
#include "stages/kinematic_stage.h"
#include "stages/noop_stage.h"
#include "stages/objects_stage.h"
#include "stages/probe_stage.h"
#include "stages/recon_stage.h"
#include "stages/stage_timeouts.h"
#include "stages/track_stage.h"
#include "stages/verdict_stages.h"

namespace doasido::stages {
namespace {

// The table entry of a stage `StageT` configured by `ConfigT` from section
// `name`.
template <typename StageT, typename ConfigT>
StageEntry Entry(const std::string& name, std::string summary, std::vector<StageReason> reasons,
                 bool in_filters_preset, double timeout_s,
                 bool decides_from_measurements = false) {
  static_assert(HasConfigCheck<ConfigT>, "every stage config states its valid ranges");
  return {.name = name,
          .summary = std::move(summary),
          .reasons = std::move(reasons),
          .in_filters_preset = in_filters_preset,
          .make = [name](const Json& config) -> std::unique_ptr<Stage> {
            ConfigT c;
            ReadCheckedSection(config, name, c);
            // A stage that also reads other sections gets the whole file.
            if constexpr (std::is_constructible_v<StageT, ConfigT, const Json&>) {
              return std::make_unique<StageT>(c, config);
            } else {
              return std::make_unique<StageT>(c);
            }
          },
          .check =
              [name](const Json& config) {
                ConfigT c;
                ReadCheckedSection(config, name, c);
              },
          .decides_from_measurements = decides_from_measurements,
          .timeout_s = timeout_s};
}

}  // namespace

const std::vector<StageEntry>& StageTable() {
  using namespace filters;
  constexpr double kMinute = 60, kHour = 3600;
  static const std::vector<StageEntry> kTable = [&] {
    std::vector<StageEntry> table = {
      Entry<DownloadStage, ingest::DownloadConfig>(
          ingest::kDownloadStageName,
          "fetches clips listed by URL into the media folder (libcurl, or a yt-dlp command "
          "template for sites); local videos pass at once",
          {},
          true, 4 * kHour),
      Entry<ProbeStage, video::ProbeConfig>(
          kProbeStageName,
          "size, fps, frame count, rotation and codec; rejects spans outside the video",
          {{kReasonSpanOutsideVideo, "clip span outside the video"}}, true,
          kMinute),
      Entry<ExternalDetectorStage, ExternalDetectorConfig>(
          kExternalDetectorStageName,
          "runs an external hand-object detector command and stores its 100DOH-format boxes",
          {{kReasonNoDetector, "no detector command"}},
          false, kHour),
      Entry<AnalyzeStage, AnalyzeConfig>(
          kAnalyzeStageName,
          "decodes the clip once at ~256 px and records every filter's per-frame signals", {}, true,
          kHour),
      Entry<ShotBoundaryStage, ShotBoundaryConfig>(
          kShotBoundaryStageName, "trims a clip to its longest shot, or rejects it across a cut",
          {{kReasonShotBoundary, "shot boundary / cut"},
           {kReasonTrimmed, "trimmed to its longest shot"}},
          true, kMinute, true),
      Entry<InteractionStage, InteractionConfig>(
          kInteractionStageName, "rejects clips without hand-object contact",
          {{kReasonNoInteraction, "no hand-object interaction"},
           {kReasonNoDetections, "no detections"}},
          true, kMinute, true),
      Entry<OutOfFrameStage, OutOfFrameConfig>(
          kOutOfFrameStageName, "rejects clips whose hand or touched object leaves the frame",
          {{kReasonOutOfFrame, "hand or object out of frame"},
           {kReasonNoDetections, "no detections"}},
          true, kMinute, true),
      Entry<ActivityStage, ActivityConfig>(
          kActivityStageName, "rejects clips with no motion in the hand region",
          {{kReasonNoActivity, "no activity"}}, true, kMinute, true),
      Entry<CameraMotionStage, CameraMotionConfig>(
          kCameraMotionStageName, "rejects (or flags) clips whose camera pans, shakes or zooms",
          {{kReasonCameraMotion, "camera motion"},
           {kReasonCameraMotionUnknown, "camera motion unknown"}},
          true, kMinute, true),
      Entry<HandsStage, hands::HandsConfig>(
          hands::kHandsStageName,
          "MediaPipe hand tracking on every kept frame, metric 3D by PnP and a Ceres skeleton "
          "fit: the hand part of a clip bundle",
          {{kReasonNoHands, "no hands found"}},
          false, kHour),
      Entry<ObjectsStage, objects::ObjectsConfig>(
          objects::kObjectsStageName,
          "lifts the category models' box keypoints (cups, shoes, chairs, cameras) to a metric "
          "6D pose per frame, sized by the touching hand or a category prior: the object part "
          "of a clip bundle",
          {{kReasonNoKnownObject, "no object of a known category (hand-only)"}},
          false, kHour),
      Entry<BundleStage, BundleStageConfig>(
          recon::kBundleStageName,
          "runs the model command (per clip, or a server started once per worker) that writes "
          "the clip bundle (or checks the bundle the list names)",
          {},
          false, 2 * kHour),
      Entry<TrackStage, TrackStageConfig>(
          kTrackStageName,
          "tracks the object frame by frame by guided flow sampling (seed 3.1): a velocity "
          "server, or the bundle's pose candidates as the model",
          {},
          false, kHour),
      Entry<ReconStage, recon::ReconStageConfig>(
          recon::kReconStageName,
          "aligns hand and object to one metric scale, gravity-aligns: the 4D reconstruction",
          {{kReasonNoObject, "no object"},
           {kReasonNoHands, "no hands found"},
           {kReasonTooFewAlignedFrames, "too few aligned frames"},
           {kReasonScaleInconsistent, "object scale inconsistent"}},
          false, 30 * kMinute),
      Entry<KinematicStage, KinematicStageConfig>(
          retarget::kKinematicStageName,
          "fingertip retargeting of the reconstructed hands onto robot hands (MuJoCo); a lone "
          "left hand with its scene mirrored onto the right one",
          {{kReasonNoHand, "no hand to retarget"},
           {kReasonKinematicError, "large fingertip error"}},
          false, 30 * kMinute),
      Entry<DynamicRetargetStage, retarget::DynamicRetargetConfig>(
          retarget::kRetargetStageName,
          "dynamics-aware retargeting of the recon artifact: annealed sampling in MuJoCo (seed "
          "3.2)",
          {{kReasonTrackingFailed, "the robot does not track the motion"},
           {kReasonNoObject, "no object"},
           {kReasonNoHands, "no hands found"},
           {kReasonHandOnlyKinematic, "hand-only: keeps its kinematic trajectory"}},
          false, 2 * kHour),
      Entry<NoopStage, NoopConfig>(kNoopStageName,
                                   "does nothing for work_ms milliseconds (queue diagnostics)", {},
                                   false, kMinute),
    };
    table[0].deterministic = false;  // the download stage: the network may answer next time
    return table;
  }();
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

std::vector<std::string> FiltersPipeline() {
  std::vector<std::string> names;
  for (const auto& entry : StageTable()) {
    if (entry.in_filters_preset) names.push_back(entry.name);
  }
  return names;
}

std::vector<std::string> DefaultPipeline() {
  std::vector<std::string> names = FiltersPipeline();
  // The method's chain after the filters (seed sections 3.1 and 3.2).
  // The objects stage sits between hands and bundle: the bundle stage joins
  // its object to the hands stage's hands when no list row or model names one.
  for (const char* stage : {hands::kHandsStageName, objects::kObjectsStageName, recon::kBundleStageName,
                            recon::kReconStageName, retarget::kKinematicStageName,
                            retarget::kRetargetStageName}) {
    names.push_back(stage);
  }
  return names;
}

const std::map<std::string, std::vector<std::string>>& PipelinePresets() {
  static const std::map<std::string, std::vector<std::string>> kPresets = {
      {kPresetDefault, DefaultPipeline()}, {kPresetFilters, FiltersPipeline()}};
  return kPresets;
}

std::vector<std::string> ExpandPipeline(const std::vector<std::string>& words) {
  std::vector<std::string> pipeline;
  std::map<std::string, std::string> preset_of;  // stage -> the preset word that gave it
  for (const auto& word : words) {
    const auto preset = PipelinePresets().find(word);
    const bool is_preset = preset != PipelinePresets().end();
    for (const auto& stage : is_preset ? preset->second : std::vector<std::string>{word}) {
      if (std::find(pipeline.begin(), pipeline.end(), stage) != pipeline.end()) {
        const std::string holder = is_preset ? word : preset_of[stage];
        throw Error("bad_pipeline",
                    "stage '" + stage + "' is listed twice" +
                        (holder.empty() ? "" : " (preset '" + holder + "' holds it)"),
                    {.field = "pipeline"});
      }
      if (is_preset) preset_of[stage] = word;
      try {
        MakeStage(stage, Json::object());  // a known name, else unknown_stage listing them
      } catch (const Error& e) {
        if (e.code() != "unknown_stage") throw;
        throw Error(e.code(), e.message() + "; presets: " + kPresetDefault + ", " + kPresetFilters,
                    e.site());
      }
      pipeline.push_back(stage);
    }
  }
  return pipeline;
}

std::vector<StageReason> StageReasons() {
  // The filters' reasons first: those are the flags a person reviews, and
  // the page's number keys pick the first nine.
  std::vector<StageReason> out;
  for (const bool filters_pass : {true, false}) {
    for (const auto& entry : StageTable()) {
      if (entry.decides_from_measurements != filters_pass) continue;
      for (const auto& reason : entry.reasons) {
        const bool seen = std::any_of(out.begin(), out.end(),
                                      [&](const StageReason& r) { return r.code == reason.code; });
        if (!seen) out.push_back(reason);
      }
    }
  }
  return out;
}

std::map<std::string, std::string> ReviewDefaultReasons() {
  std::map<std::string, std::string> out;
  for (const auto& entry : StageTable()) {
    if (entry.decides_from_measurements && !entry.reasons.empty()) {
      out[entry.name] = entry.reasons.front().code;
    }
  }
  return out;
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
  known.push_back(kTimeoutsSection);
  for (const auto& entry : StageTable()) known.push_back(entry.name);
  for (const auto& [section, value] : config.items()) {
    if (std::find(known.begin(), known.end(), section) != known.end()) continue;
    std::string list;
    for (const auto& name : known) list += (list.empty() ? "" : ", ") + name;
    throw Error("bad_config", "unknown section [" + section + "] (known: " + list + ")",
                {.field = section});
  }
  for (const auto& entry : StageTable()) entry.check(config);
  CheckStageTimeouts(config);
}

}  // namespace doasido::stages
