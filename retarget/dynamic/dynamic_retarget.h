// A reconstruction (recon/reconstruction.h) to a physically simulated robot
// trajectory, the whole of seed section 3.2:
//   1. the reference is checked (CheckReference) and invalid object frames
//      held;
//   2. the object mesh becomes a simulation scene at its frame-0 pose
//      (scene_builder.h; the reconstruction's floor is z = 0 already);
//   3. the hand is retargeted kinematically onto the robot
//      (KinematicRetargeter), frames labelled in-hand / resting;
//   4. annealed sampling tracks hand and object in simulation
//      (annealed_sampler.h);
//   5. the simulated state is read back at the reference's frame rate and
//      scored against the reconstructed object poses (retarget_metrics.h).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/error.h"
#include "recon/reconstruction.h"
#include "retarget/dynamic/annealed_sampler.h"
#include "retarget/dynamic/dynamic_reference.h"
#include "retarget/dynamic/retarget_metrics.h"
#include "retarget/dynamic/sampler_ladder.h"
#include "retarget/kinematic/kinematic_retarget.h"
#include "retarget/scene/scene_builder.h"
#include "robot/embodiment.h"

namespace doasido::retarget {

struct DynamicRetargetConfig {
  std::string hand = "sharpa_right";  // embodiment name or description path
  // "" retargets the right hand only; a robot hand (e.g. "sharpa_left")
  // retargets both hands of a reconstruction that has a left one, this
  // hand on the left and `hand` on the right (bimanual_retarget.h).
  std::string left_hand;
  std::string robots_dir;             // "" = DefaultRobotsDir()
  // kLadderPreset ("ladder", the default) retargets each clip along
  // `ladder` (sampler_ladder.h); a preset name ("fast", "medium", "seed":
  // annealed_sampler.h SamplerPreset) runs that preset alone; "" runs
  // `sampler` as written.
  std::string preset = kLadderPreset;
  // Rungs, cheapest first: preset names, or kSamplerRung ("sampler") for
  // `sampler` as written. A clip re-runs at the next rung only when it fails.
  std::vector<std::string> ladder = {"fast", "medium", "seed"};
  AnnealedSamplerConfig sampler;  // threads and seed apply to every preset
  KinematicConfig kinematic;
  SceneConfig scene;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(DynamicRetargetConfig, hand, left_hand, robots_dir, preset,
                                                ladder, sampler, kinematic, scene)
void CheckConfig(const DynamicRetargetConfig& c, const std::string& section);

// The rung names `config` runs, in order: `ladder` for kLadderPreset, else
// the one preset ("" -> kSamplerRung).
std::vector<std::string> LadderRungs(const DynamicRetargetConfig& config);
// The sampler settings of rung `rung` (a preset with `config.sampler`'s
// threads and seed, or kSamplerRung: `config.sampler`).
AnnealedSamplerConfig RungSampler(const DynamicRetargetConfig& config, const std::string& rung);
// `config` running rung `rung` alone.
DynamicRetargetConfig AtRung(const DynamicRetargetConfig& config, const std::string& rung);
// The sampler settings `config` asks for: its first rung's.
AnnealedSamplerConfig EffectiveSampler(const DynamicRetargetConfig& config);

struct DynamicRetargetRun {
  HandTrajectory trajectory;   // at the reference fps: qpos, ctrl, object poses, metrics
  HandTrajectory kinematic;    // the kinematic reference it tracked
  TrackingMetrics metrics;
  SamplerStats stats;
  std::string robot_scene_xml; // the hand + object scene it ran in
  int in_hand_frames = 0;      // frames a hand holds the object off the floor
  // Per frame, the robot fingertips the kinematic reference put on the
  // object (KinematicConfig contact_weight; all 0 when off).
  std::vector<int> grasp_contacts;
};

// `e`, naming `label` as its clip when it names none.
Error NamingClip(const Error& e, const std::string& label);

// The simulated trajectory (result's states) at the reference's frames, in
// the kinematic trajectory's variable order, with the controls (step 5).
HandTrajectory SimulatedTrajectory(const mjModel* m, const SceneIndex& index, const DynamicReference& ref,
                                   const DynamicResult& result, const HandTrajectory& kinematic);

// What a clip's retargeting keeps of its input between rungs: the
// reconstruction and object mesh (not owned), the label naming the clip in
// errors, and the object poses with invalid frames filled (FilledObjectPoses).
struct ClipObject {
  const recon::Reconstruction& r;
  const TriMesh& mesh;
  std::string label;
  std::vector<Pose> object;
};

// The object's tracking metrics of `simulated` (SimulatedTrajectory)
// against the clip's object poses, over its valid object frames.
TrackingMetrics ObjectMetrics(const ClipObject& clip, const HandTrajectory& simulated);

// Steps 1-3 of one clip, done once and tracked at any sampler setting
// (steps 4-5): the ladder's rungs differ only in the sampler, so they share
// the scene, the compiled model and the kinematic reference (building them
// costs seconds a rung). `r` and `mesh` must outlive it. Throws as
// RetargetReconstruction, naming `label`.
class ClipRetarget {
 public:
  ClipRetarget(const recon::Reconstruction& r, const TriMesh& mesh, const Embodiment& hand,
               const DynamicRetargetConfig& config, const std::filesystem::path& scene_dir,
               const std::string& label);
  // Steps 4-5 with `sampler`; the same result as RetargetReconstruction
  // with a config whose effective sampler is `sampler`.
  DynamicRetargetRun Track(const AnnealedSamplerConfig& sampler,
                           const std::function<void(int, int)>& progress = {},
                           const WindowTraceFn& trace = {}) const;

 private:
  ClipObject clip_;
  HandModel model_;
  HandTrajectory kinematic_;
  std::vector<int> grasp_contacts_;
};

// Runs steps 1-5 (ClipRetarget, then Track at EffectiveSampler(config)).
// `mesh` is the object in its own frame; scene files go to `scene_dir`.
// `label` names the clip in errors. Throws Error("bad_reference"),
// Error("bad_mesh") (decomposition failed), Error("unstable_simulation").
DynamicRetargetRun RetargetReconstruction(const recon::Reconstruction& r, const TriMesh& mesh,
                                          const Embodiment& hand,
                                          const DynamicRetargetConfig& config,
                                          const std::filesystem::path& scene_dir,
                                          const std::string& label,
                                          const std::function<void(int, int)>& progress = {});

}  // namespace doasido::retarget
