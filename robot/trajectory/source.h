// Where a clip's robot trajectory is: the output of the clip's run of its
// trajectory stage (TrajectoryStageOf, robot/trajectory/format.h) that the
// database records as done with verdict pass (Database::RecordedOutput).
// Both trajectory stages write HandTrajectory JSON; the scene the
// trajectory was retargeted in is kSceneFolder/kSceneFile beside it (or in
// the kinematic stage's folder).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "db/database.h"

namespace doasido::retarget {

struct TrajectoryFiles {
  std::string stage;                 // the stage whose trajectory this is
  std::int64_t run_id = 0;           // its run, when read from a database
  std::string param_hash;            // the parameters of that run
  std::filesystem::path trajectory;  // .../trajectory.json
  std::filesystem::path scene_dir;   // folder holding scene.xml, or empty
};

// For a trajectory.json given directly: scene/ beside it when present.
TrajectoryFiles FilesBeside(const std::filesystem::path& trajectory_json);
// For a clip of `db`: the trajectory of the recorded run of the trajectory
// stage, when that run is done with verdict pass (or flag, when
// `allow_flag`: /verify shows those) and wrote trajectory.json; else
// std::nullopt with *why (when given) naming the run and what it is.
std::optional<TrajectoryFiles> FindTrajectoryFiles(Database& db, ClipId clip,
                                                   std::string* why = nullptr,
                                                   bool allow_flag = false);

// The text of <scene_dir>/scene.xml, or "" when scene_dir is empty.
std::string ReadSceneXml(const std::filesystem::path& scene_dir);

}  // namespace doasido::retarget
