#include "deploy/trajectory_source.h"

#include "core/error.h"
#include "core/file_text.h"
#include "retarget/kinematic_stage.h"

namespace doasido::deploy {

TrajectoryFiles FilesBeside(const std::filesystem::path& trajectory_json) {
  TrajectoryFiles f;
  f.trajectory = trajectory_json;
  const std::filesystem::path scene = trajectory_json.parent_path() / "scene";
  if (std::filesystem::exists(scene / "scene.xml")) f.scene_dir = scene;
  return f;
}

std::optional<TrajectoryFiles> FindTrajectoryFiles(const Database& db, ClipId clip) {
  const std::filesystem::path kinematic = db.ArtifactDir(clip, retarget::kKinematicStageName);
  for (const char* stage : {retarget::kRetargetStageName, retarget::kKinematicStageName}) {
    const std::filesystem::path dir = db.ArtifactDir(clip, stage);
    if (!std::filesystem::exists(dir / "trajectory.json")) continue;
    TrajectoryFiles f = FilesBeside(dir / "trajectory.json");
    f.stage = stage;
    if (f.scene_dir.empty() && std::filesystem::exists(kinematic / "scene" / "scene.xml")) {
      f.scene_dir = kinematic / "scene";
    }
    return f;
  }
  return std::nullopt;
}

std::string ReadSceneXml(const std::filesystem::path& scene_dir) {
  if (scene_dir.empty()) return {};
  return ReadFileOrThrow(scene_dir / "scene.xml", "io", "cannot read scene");
}

}  // namespace doasido::deploy
