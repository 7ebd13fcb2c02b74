// Two hands and the object in one simulation (seed section 3.2 for bimanual
// clips): a reconstruction with both hands becomes one robot trajectory of
// a left and a right robot hand, each on its own floating wrist, optimised
// together by the annealed sampler with the seed's components.
//
//   1. the reference is checked (both hands seen somewhere, finite) and
//      invalid object frames held;
//   2. the object becomes a scene (scene_builder.h), as for one hand;
//   3. each hand is retargeted kinematically onto its robot hand in a scene
//      of its own with the object (KinematicRetargeter, grasp terms when
//      configured);
//   4. one model holds both hands (each with its floating wrist, names
//      prefixed "l_" and "r_": PrefixMjcfNames) and the object; the two
//      kinematic references become one reference over all actuators, a
//      step "in hand" when either hand is (the transition reward);
//   5. annealed sampling tracks it (annealed_sampler.h) and the simulated
//      state is read back at the reference's frame rate; metrics for the
//      object (retarget_metrics.h) and, per hand, how far its simulated
//      wrist stays from its reference.
#pragma once

#include <filesystem>
#include <string>

#include "recon/reconstruction.h"
#include "retarget/dynamic/dynamic_retarget.h"

namespace doasido::retarget {

struct BimanualRun {
  // Both hands at the reference fps: qpos_names and ctrl_names prefixed
  // kLeftPrefix / kRightPrefix, object poses, metrics.
  HandTrajectory trajectory;
  HandTrajectory left_kinematic, right_kinematic;  // each hand's kinematic reference
  TrackingMetrics metrics;                         // the object's
  double left_wrist_error = 0, right_wrist_error = 0;  // m, mean over frames each hand was seen
  int left_in_hand_frames = 0, right_in_hand_frames = 0;
  SamplerStats stats;
  std::string robot_scene_xml;  // both hands + object
};

// Steps 1-4 of one clip, done once and tracked at any sampler setting
// (step 5), as ClipRetarget (dynamic_retarget.h) for one hand. `r` and
// `mesh` must outlive it.
class BimanualRetarget {
 public:
  BimanualRetarget(const recon::Reconstruction& r, const TriMesh& mesh, const Embodiment& left,
                   const Embodiment& right, const DynamicRetargetConfig& config,
                   const std::filesystem::path& scene_dir, const std::string& label);
  BimanualRun Track(const AnnealedSamplerConfig& sampler,
                    const std::function<void(int, int)>& progress = {}) const;

 private:
  ClipObject clip_;
  HandTrajectory left_kinematic_, right_kinematic_;
  std::string robot_scene_xml_;
  ModelPtr model_;
};

// Runs steps 1-5 (BimanualRetarget, then Track at EffectiveSampler(config)).
// `r` must carry a left hand (left_valid non-empty);
// `left` and `right` are the robot hands (e.g. sharpa_left, sharpa_right;
// `doasido hand mirror` makes one from the other). Throws as
// RetargetReconstruction, and Error("bad_reference") for a missing hand.
BimanualRun RetargetBimanual(const recon::Reconstruction& r, const TriMesh& mesh, const Embodiment& left,
                             const Embodiment& right, const DynamicRetargetConfig& config,
                             const std::filesystem::path& scene_dir, const std::string& label,
                             const std::function<void(int, int)>& progress = {});

}  // namespace doasido::retarget
