#include "robot/trajectory/source.h"

#include "core/error.h"
#include "core/file_text.h"
#include "robot/trajectory/format.h"

namespace doasido::retarget {

TrajectoryFiles FilesBeside(const std::filesystem::path& trajectory_json) {
  TrajectoryFiles f;
  f.trajectory = trajectory_json;
  const std::filesystem::path scene = trajectory_json.parent_path() / kSceneFolder;
  if (std::filesystem::exists(scene / kSceneFile)) f.scene_dir = scene;
  return f;
}

std::optional<TrajectoryFiles> FindTrajectoryFiles(Database& db, ClipId clip, std::string* why,
                                                   bool allow_flag) {
  const std::string of_pipeline = TrajectoryStageOf(db.Pipeline());
  const bool dynamic = of_pipeline == kRetargetStageName;
  // A pipeline without either stage is asked for the kinematic one, whose
  // missing run RecordedOutput then names.
  const std::string stage = of_pipeline.empty() ? kKinematicStageName : of_pipeline;
  const auto run = db.RecordedOutput(clip, stage, allow_flag, why);
  if (!run) return std::nullopt;
  if (!std::filesystem::exists(run->dir / kTrajectoryFile)) {
    if (why) *why = "clip " + std::to_string(clip) + "'s " + stage + " run " +
                    std::to_string(run->run_id) + " wrote no " + kTrajectoryFile + " in " + run->dir.string();
    return std::nullopt;
  }
  TrajectoryFiles f = FilesBeside(run->dir / kTrajectoryFile);
  f.stage = stage;
  f.run_id = run->run_id;
  f.param_hash = run->param_hash;
  if (f.scene_dir.empty() && dynamic) {
    // The dynamic stage retargets in the kinematic stage's scene.
    const auto kinematic = db.RecordedOutput(clip, kKinematicStageName, true);
    if (kinematic && std::filesystem::exists(kinematic->dir / kSceneFolder / kSceneFile)) {
      f.scene_dir = kinematic->dir / kSceneFolder;
    }
  }
  return f;
}

std::string ReadSceneXml(const std::filesystem::path& scene_dir) {
  if (scene_dir.empty()) return {};
  return ReadFileOrThrow(scene_dir / kSceneFile, "io", "cannot read scene");
}

}  // namespace doasido::retarget
