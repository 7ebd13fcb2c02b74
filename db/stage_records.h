// The records of one stage run that the database loads and records: the
// clip's context a run starts from (Database::LoadContext) and the result
// it ends with (Database::Complete). The Stage interface that turns
// one into the other, and the stages themselves, are in stages/ (stages/stage.h).
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/config.h"
#include "core/records.h"

namespace doasido {

struct ClipContext {
  ClipRecord clip;
  VideoRecord video;
  std::vector<Detection> detections;
  // Measurements of the stages this clip already passed, by stage name.
  std::map<std::string, Json> measurements;
  // The folder the run writes into, created before Run: a fresh hidden
  // sibling of the stage's published folder <artifact root>/<clip>/<stage>/,
  // renamed into place when the run succeeds (Database::PublishArtifacts).
  std::filesystem::path artifact_dir;
  // Published folders of the clip's earlier stages whose recorded runs are
  // done with verdict pass or flag (Database::RecordedOutput), by stage;
  // read them through stages::SiblingArtifactDir.
  std::map<std::string, std::filesystem::path> inputs;
};

struct StageResult {
  Verdict verdict = Verdict::kPass;
  std::string reason;  // machine-readable reason code, e.g. "camera_motion"
  // Raw signals and summary numbers, kept so verdicts can be re-decided
  // without running the stage again.
  Json measurements = Json::object();
  // Files the stage wrote, relative to artifact_dir, with a kind each.
  std::vector<std::pair<std::string, std::string>> artifacts;  // (kind, path)
  std::optional<VideoInfo> video_info;  // the probe stage fills this in
  std::vector<Detection> detections;    // detectors may add detections
};

}  // namespace doasido
