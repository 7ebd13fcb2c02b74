// The files of a robot trajectory: the HandTrajectory JSON both trajectory
// stages write, and the scene it was retargeted in (kSceneFolder/kSceneFile
// beside it, or in the kinematic stage's folder). Where a clip's trajectory
// is in a database (its trajectory stage's recorded run) is
// review/trajectory_lookup.h, above the database.
#pragma once

#include <filesystem>
#include <optional>
#include <string>


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
// The text of <scene_dir>/scene.xml, or "" when scene_dir is empty.
std::string ReadSceneXml(const std::filesystem::path& scene_dir);

}  // namespace doasido::retarget
