// Smoothing the wrist path before planning (deploy plan step 0): a wrist
// path tracked from video jitters from frame to frame (02_cups' hand-only
// trajectory moves its wrist by up to 4 cm between frames where the hand
// is still), and the re-timing (time_scaling.h) must slow the whole clip
// down until the arm can follow every jolt of that noise. Noise is fast,
// a hand's motion slow: a zero-phase low-pass filter separates them.
//
//   positions: a Gaussian kernel over time with sigma = sqrt(ln 2) /
//     (2 pi cutoff_hz), i.e. a gain of 1/sqrt(2) at cutoff_hz (zero phase:
//     the kernel is symmetric, so the filtered path neither lags nor leads),
//     the ends extended by point reflection (2 x_0 - x_k), which keeps a
//     straight start or end straight;
//   rotations: at each frame the same kernel's weighted mean of the other
//     frames' rotations relative to it (log / exp about that frame);
//   bound: a frame whose smoothed position moved more than `tolerance`
//     from the trajectory's (or its rotation more than
//     `rotation_tolerance`) is pulled back along that correction to the
//     bound, so the arm never leaves the recorded wrist by more than that.
//
// Applied to trajectories without an object (hand-only ones: nothing the
// hand touches depends on the exact path); `with_object` applies it to the
// others too, within the same bound. cutoff_hz = 0 turns it off.
#pragma once

#include <string>

#include "core/config.h"
#include "robot/trajectory/format.h"

namespace doasido::deploy {

struct WristSmoothingConfig {
  double cutoff_hz = 2.0;           // Hz; 0: off
  double tolerance = 0.005;         // m the smoothed wrist may leave the trajectory's
  double rotation_tolerance = 0.2;  // rad the same for its rotation
  bool with_object = false;         // also smooth trajectories with an object
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(WristSmoothingConfig, cutoff_hz, tolerance, rotation_tolerance,
                                                with_object)
void CheckConfig(const WristSmoothingConfig& c, const std::string& section);

// What the smoothing did to a plan's wrist path (the plan file's
// "wrist_smoothing").
struct WristSmoothingReport {
  bool applied = false;
  double cutoff_hz = 0;
  double position_deviation_max = 0;  // m, the largest move of a frame's wrist
  double rotation_deviation_max = 0;  // rad
  int bounded_frames = 0;             // frames pulled back to a tolerance
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(WristSmoothingReport, applied, cutoff_hz, position_deviation_max,
                                                rotation_deviation_max, bounded_frames)

// `t` with its floating wrist (doasido_wrist_x..rz) smoothed as above, or
// `t` unchanged when the config or the trajectory says not to (report's
// `applied` false). Throws Error("bad_trajectory") for a trajectory
// without a floating wrist.
retarget::HandTrajectory SmoothWrist(const retarget::HandTrajectory& t, const WristSmoothingConfig& config,
                                     WristSmoothingReport* report);

}  // namespace doasido::deploy
