#include "deploy/trajectory_source.h"

#include <algorithm>

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

std::optional<TrajectoryFiles> FindTrajectoryFiles(Database& db, ClipId clip, std::string* why,
                                                   bool allow_flag) {
  const auto pipeline = db.Pipeline();
  const bool dynamic = std::find(pipeline.begin(), pipeline.end(), retarget::kRetargetStageName) !=
                       pipeline.end();
  const std::string stage = dynamic ? retarget::kRetargetStageName : retarget::kKinematicStageName;
  const auto run = db.RecordedOutput(clip, stage, allow_flag, why);
  if (!run) return std::nullopt;
  if (!std::filesystem::exists(run->dir / "trajectory.json")) {
    if (why) *why = "clip " + std::to_string(clip) + "'s " + stage + " run " +
                    std::to_string(run->run_id) + " wrote no trajectory.json in " + run->dir.string();
    return std::nullopt;
  }
  TrajectoryFiles f = FilesBeside(run->dir / "trajectory.json");
  f.stage = stage;
  f.run_id = run->run_id;
  f.param_hash = run->param_hash;
  if (f.scene_dir.empty() && dynamic) {
    // The dynamic stage retargets in the kinematic stage's scene.
    const auto kinematic = db.RecordedOutput(clip, retarget::kKinematicStageName, true);
    if (kinematic && std::filesystem::exists(kinematic->dir / "scene" / "scene.xml")) {
      f.scene_dir = kinematic->dir / "scene";
    }
  }
  return f;
}

std::string ReadSceneXml(const std::filesystem::path& scene_dir) {
  if (scene_dir.empty()) return {};
  return ReadFileOrThrow(scene_dir / "scene.xml", "io", "cannot read scene");
}

}  // namespace doasido::deploy
