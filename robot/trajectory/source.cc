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

std::string ReadSceneXml(const std::filesystem::path& scene_dir) {
  if (scene_dir.empty()) return {};
  return ReadFileOrThrow(scene_dir / kSceneFile, "io", "cannot read scene");
}

}  // namespace doasido::retarget
