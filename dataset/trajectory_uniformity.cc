#include "dataset/trajectory_uniformity.h"

namespace doasido::dataset {

Mismatch TrajectoryMismatch(const retarget::HandTrajectory& t,
                            const retarget::HandTrajectory& first, const std::string& first_clip,
                            MayDiffer may_differ) {
  const std::string first_ones = "the first episode's (clip " + first_clip;
  if (t.embodiment != first.embodiment) {
    return {"embodiment", "robot " + t.embodiment + " differs from " + first_ones + ", " + first.embodiment + ")"};
  }
  if (t.fps != first.fps) {
    return {"fps", "fps " + std::to_string(t.fps) + " differs from " + first_ones + ", " +
                       std::to_string(first.fps) + ")"};
  }
  if (t.qpos_names != first.qpos_names)
    return {"qpos_names", "joints differ from " + first_ones + ")"};
  if (!may_differ.controls &&
      (t.ctrl_names != first.ctrl_names || t.ctrl.empty() != first.ctrl.empty())) {
    return {"ctrl_names", "actuators differ from " + first_ones + ")"};
  }
  if (!may_differ.object_poses && t.object_poses.empty() != first.object_poses.empty()) {
    return {"object_poses", "object poses are present in one episode and not the other"};
  }
  if (t.reference_keypoints.empty() != first.reference_keypoints.empty()) {
    return {"reference_keypoints", "hand keypoints are present in one episode and not the other"};
  }
  return {};
}

}  // namespace doasido::dataset
