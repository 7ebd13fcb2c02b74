// The `retarget` queue stage (after `recon`): the dynamics-aware
// retargeting of seed section 3.2 (dynamic_retarget.h) on the clip's
// reconstruction artifact.
//
// Input: <artifacts>/<clip>/recon/ (recon/reconstruction.h, ReadReconstruction).
// Output in artifact_dir:
//   trajectory.json / trajectory.csv  the simulated robot trajectory at the
//       reconstruction's frame rate: qpos, ctrl (position targets), object
//       pose, metrics (kinematic_retarget.h HandTrajectory; ReadTrajectoryJson
//       reads it like retarget_kinematic's)
//   kinematic_reference.json  the kinematic reference it tracked
//   scene/scene.xml + hull OBJs, robot_scene.xml  the scene it ran in
// Measurements: e_pos, e_rot, success, frames, in_hand_frames (frames the
// reference holds the object off the floor), plans, iterations, rollouts,
// sim_steps, optimizer_seconds, rollout_steps_per_second (all of the kept
// run), and the ladder's (sampler_ladder.h): rung (the kept run's rung),
// rungs_run, and per rung that ran rung_<name>_seconds (wall),
// rung_<name>_e_pos, rung_<name>_e_rot, rung_<name>_success. A clip runs
// at the ladder's first rung and at the next only while it fails.
// With config.left_hand set and a left hand in the reconstruction, both
// hands are retargeted in one scene (bimanual_retarget.h): the trajectory
// holds both (names prefixed l_ / r_, embodiment "<left>+<right>"),
// kinematic_reference.json is the right hand's and
// kinematic_reference_left.json the left's; measurements add
// left_wrist_error, right_wrist_error (m) and left_in_hand_frames.
// A lone left hand is retargeted with the whole scene mirrored onto `hand`
// (retarget/mirror_scene.h; measurement retargeted_hand "left_mirrored", else
// "right"), both hands with config.left_hand set take the two-hand scene;
// both hands without it, the one holding the object (its fingertips nearer
// the object, retarget/holding_hand.h): a left one mirrored as if alone.
// A hand-only reconstruction keeps the retarget_kinematic trajectory (pass,
// kReasonHandOnlyKinematic; reject kReasonNoObject when the pipeline has no
// retarget_kinematic before this stage).
// Verdict: pass on success (E_pos < 0.1 m and E_rot < 0.5 rad); reject with
// kReasonTrackingFailed otherwise, kReasonNoHands without any hand. Errors (the clip fails, the batch goes on):
// bad_reconstruction / bad_reference (NaN frames), bad_mesh (decomposition
// failed), unstable_simulation (NaN state).
#pragma once

#include <string>

#include "retarget/dynamic/dynamic_retarget.h"
#include "stages/recon_stage.h"
#include "stages/shared_reasons.h"
#include "stages/stage.h"

namespace doasido::stages {

// The stage's name (kRetargetStageName, robot/trajectory/format.h with the
// trajectory file names) is its queue name, config section and artifact folder.

// Reason codes of the stage's verdicts (and kReasonNoObject,
// stages/shared_reasons.h).
inline constexpr const char* kReasonTrackingFailed = "tracking_failed";
// A pass: a hand-only clip (no object to simulate) keeps its
// retarget_kinematic trajectory, copied into this stage's folder
// (measurement kMeasureTrajectorySource names the stage it came from).
inline constexpr const char* kReasonHandOnlyKinematic = "hand_only_kinematic";
inline constexpr const char* kMeasureTrajectorySource = "trajectory_source";

class DynamicRetargetStage : public Stage {
 public:
  explicit DynamicRetargetStage(retarget::DynamicRetargetConfig config = {});
  std::string Name() const override { return retarget::kRetargetStageName; }
  Json Params() const override { return config_; }
  // 2: the seed's stages (a hand near the object is no rest) and the plan
  // executed only once rolled out (issue 51): the same parameters now lift
  // what revision 1 left on the floor.
  int Revision() const override { return 2; }
  StageResult Run(const ClipContext& context) override;
  std::optional<StageResult> Redecide(const Json& measurements) const override;

 private:
  StageResult KeepKinematic(const ClipContext& context, StageResult result) const;
  retarget::DynamicRetargetConfig config_;
};

}  // namespace doasido::stages
