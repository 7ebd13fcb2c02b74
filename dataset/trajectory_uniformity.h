// Exports write a version as one dataset with one robot, one rate and one
// set of features: every episode's trajectory must agree with the first on
// what the export writes once (issue #42: a version mixing sharpa and
// allegro was written to robomimic with one embodiment attribute).
#pragma once

#include <string>

#include "robot/trajectory/format.h"

namespace doasido::dataset {

inline constexpr const char* kMixedTrajectories = "mixed_trajectories";

// The field in which `t` differs from `first` ("embodiment", "fps",
// "qpos_names", "ctrl_names", "object_poses", "reference_keypoints") with a
// sentence saying how, or {"", ""} when they agree. The sentence names
// `first_clip`, the first episode's clip, so that both clips of the pair are
// named whatever order the export reads them in. With
// `object_poses_may_differ` (the LeRobot export, which leaves the object
// feature out when any episode is hand-only) object poses are not compared.
struct Mismatch {
  std::string field;
  std::string why;
};
Mismatch TrajectoryMismatch(const retarget::HandTrajectory& t,
                            const retarget::HandTrajectory& first,
                            const std::string& first_clip,
                            bool object_poses_may_differ = false);

}  // namespace doasido::dataset
