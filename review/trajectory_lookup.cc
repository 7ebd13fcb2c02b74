#include "review/trajectory_lookup.h"

#include <filesystem>

#include "robot/trajectory/format.h"

namespace doasido::review {

std::optional<retarget::TrajectoryFiles> FindTrajectoryFiles(Database& db, ClipId clip, std::string* why,
                                                   bool allow_flag) {
  const std::string of_pipeline = retarget::TrajectoryStageOf(db.Pipeline());
  const bool dynamic = of_pipeline == retarget::kRetargetStageName;
  // A pipeline without either stage is asked for the kinematic one, whose
  // missing run RecordedOutput then names.
  const std::string stage = of_pipeline.empty() ? retarget::kKinematicStageName : of_pipeline;
  const auto run = db.RecordedOutput(clip, stage, allow_flag, why);
  if (!run) return std::nullopt;
  if (!std::filesystem::exists(run->dir / retarget::kTrajectoryFile)) {
    if (why) *why = "clip " + std::to_string(clip) + "'s " + stage + " run " +
                    std::to_string(run->run_id) + " wrote no " + retarget::kTrajectoryFile + " in " + run->dir.string();
    return std::nullopt;
  }
  retarget::TrajectoryFiles f = retarget::FilesBeside(run->dir / retarget::kTrajectoryFile);
  f.stage = stage;
  f.run_id = run->run_id;
  f.param_hash = run->param_hash;
  if (f.scene_dir.empty() && dynamic) {
    // The dynamic stage retargets in the kinematic stage's scene.
    const auto kinematic = db.RecordedOutput(clip, retarget::kKinematicStageName, true);
    if (kinematic && std::filesystem::exists(kinematic->dir / retarget::kSceneFolder / retarget::kSceneFile)) {
      f.scene_dir = kinematic->dir / retarget::kSceneFolder;
    }
  }
  return f;
}

}  // namespace doasido::review
