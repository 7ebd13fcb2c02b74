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
// `may_differ` the features an export can write for a mixed version are
// not compared (the LeRobot export leaves the object feature out when any
// episode is hand-only, and takes the next frame's joints as the action
// when not every episode recorded actuator targets).
struct MayDiffer {
  bool object_poses = false;
  bool controls = false;
};
struct Mismatch {
  std::string field;
  std::string why;
};
Mismatch TrajectoryMismatch(const retarget::HandTrajectory& t,
                            const retarget::HandTrajectory& first,
                            const std::string& first_clip, MayDiffer may_differ = {});

}  // namespace doasido::dataset
