// Trajectories brought to another frame rate, for exports that hold one
// rate per dataset (LeRobot): `dataset export --fps`. Clips from different
// cameras (29.97, 30, 25 fps) become one dataset this way.
//
// Output frame k sits at time k / fps; its source position is
// p = k * from_fps / fps (a fractional source frame), for k while p is
// within the last source frame. Joint positions and controls are linear
// between the two source frames around p; object poses interpolate
// translation linearly and rotation by slerp; a frame is valid when both
// neighbours are; fingertip errors, reference keypoints and the rest come
// from the nearest source frame.
#pragma once

#include <cstdint>
#include <vector>

#include "robot/trajectory/format.h"

namespace doasido::dataset {

// The source positions of the output frames (see above). Empty for 0 frames.
std::vector<double> ResamplePositions(std::size_t frames, double from_fps, double to_fps);

// `t` at `fps` (t unchanged when its rate already is `fps`).
retarget::HandTrajectory ResampleTrajectory(const retarget::HandTrajectory& t, double fps);

}  // namespace doasido::dataset
