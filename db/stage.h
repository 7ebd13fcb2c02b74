// The contract every queue stage implements.
//
// A stage is a pure function of one clip and its parameters: the worker
// loads a ClipContext from the database, calls Run, and records the
// StageResult in the same transaction that completes the stage run. Stages
// never open the database and never call each other; they meet through the
// database (detections, earlier stages' measurements) and the clip's
// artifact folder.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "db/records.h"

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
  // read them through recon::SiblingArtifactDir.
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

class Stage {
 public:
  virtual ~Stage() = default;
  virtual std::string Name() const = 0;
  // The effective parameters; their ParamHash identifies a result.
  virtual Json Params() const = 0;
  // Runs on one clip. Throws doasido::Error for bad input; the worker
  // records the message and retries up to the attempt limit.
  virtual StageResult Run(const ClipContext& context) = 0;
  // Re-decides a verdict from stored measurements (for re-thresholding).
  // Stages whose verdict is not a threshold return nullopt.
  virtual std::optional<StageResult> Redecide(const Json& measurements) const {
    (void)measurements;
    return std::nullopt;
  }
};

}  // namespace doasido
