// Where a clip's robot trajectory is: the dynamics-aware `retarget` stage's
// artifact folder when it has a trajectory.json, else the kinematic stage's
// (retarget/kinematic_stage.h). Both write retarget::HandTrajectory JSON;
// the scene the trajectory was retargeted in is scene/scene.xml beside it
// (or in the kinematic stage's folder).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "db/database.h"

namespace doasido::deploy {

// The dynamics stage's queue and artifact name. Its own header (retarget/)
// is written in parallel; the lead points this at that constant on merge.
inline constexpr const char* kDynamicsStageName = "retarget";

struct TrajectoryFiles {
  std::string stage;                 // the stage whose trajectory this is
  std::filesystem::path trajectory;  // .../trajectory.json
  std::filesystem::path scene_dir;   // folder holding scene.xml, or empty
};

// For a trajectory.json given directly: scene/ beside it when present.
TrajectoryFiles FilesBeside(const std::filesystem::path& trajectory_json);
// For a clip of `db`; std::nullopt when neither stage wrote a trajectory.
std::optional<TrajectoryFiles> FindTrajectoryFiles(const Database& db, ClipId clip);

// The text of <scene_dir>/scene.xml, or "" when scene_dir is empty.
std::string ReadSceneXml(const std::filesystem::path& scene_dir);

}  // namespace doasido::deploy
