// The `retarget_kinematic` queue stage: a clip's reconstructed right hand
// (and object) become the reference robot trajectory and the simulation
// scene the dynamics-aware optimiser starts from (seed section 3.2).
//
// Input: the `recon` stage's artifact <artifacts>/<clip>/recon/
// (recon/reconstruction.h: metric, gravity-aligned hands and object, or the
// hands alone; frames without an object pose hold the previous one) when it
// exists, else the clip bundle (stages/clip_inputs.h LoadClipBundle):
// hands.npz, object/poses.npz, object/mesh.obj, gravity.npz, meta.json fps,
// put in a world frame whose +z is up (mean of gravity.npz, else the
// camera's -y) with the floor z = 0 touching the object's lowest point in
// the first frame (or 5 cm below the lowest hand keypoint without object).
//
// Hands: trajectory.json is the right hand on `hand`; a clip whose only
// hand is the left has it mirrored (x -> -x in the world frame) onto `hand`
// with the whole scene, object mesh and poses included
// (retarget/mirror_scene.h), so that every episode of a dataset has one
// robot (measurement
// retargeted_hand "right" or "left_mirrored"). When both hands are seen and
// `left_hand` is set, the left hand is also retargeted onto `left_hand`
// into trajectory_left.json (measurements left_*).
// Output in artifact_dir: trajectory.json and trajectory.csv
// (kinematic_retarget.h HandTrajectory: robot qpos per frame, object poses
// in the world frame, none for a hand-only clip), and with an object
// scene/scene.xml + hull OBJs (scene_builder.h) and robot_scene.xml (hand
// with floating wrist + scene).
// Verdict: pass, or flag ("kinematic_error") when the mean fingertip error
// exceeds flag_fingertip_error; reject ("no_hand") without any hand.
// With an object, the object's poses go with the right hand's trajectory.
#pragma once

#include <string>

#include "core/config.h"
#include "retarget/config_checks.h"
#include "retarget/kinematic/kinematic_retarget.h"
#include "retarget/scene/scene_builder.h"
#include "stages/stage.h"

namespace doasido::stages {

// The stage's name (kKinematicStageName, robot/trajectory/format.h with the
// trajectory file names) is its queue name, config section and artifact folder.
inline constexpr const char* kLeftTrajectoryFile = "trajectory_left.json";
inline constexpr const char* kReasonNoHand = "no_hand";
// Flag: the mean fingertip error exceeds flag_fingertip_error.
inline constexpr const char* kReasonKinematicError = "kinematic_error";
inline constexpr const char* kMeasureRetargetedHand = "retargeted_hand";
inline constexpr const char* kHandRight = "right";
inline constexpr const char* kHandLeftMirrored = "left_mirrored";

struct KinematicStageConfig {
  std::string hand = "sharpa_right";  // embodiment name or description path
  std::string left_hand = "sharpa_left";  // the left hand's robot; "" = right hand only
  std::string robots_dir;             // folder of descriptions; "" = DefaultRobotsDir()
  double flag_fingertip_error = 0.02; // m, mean over frames
  retarget::KinematicConfig kinematic;
  retarget::SceneConfig scene;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(KinematicStageConfig, hand, left_hand, robots_dir,
                                                flag_fingertip_error, kinematic, scene)
// Also checks the nested kinematic and scene tables (retarget/config_checks.h).
void CheckConfig(const KinematicStageConfig& c, const std::string& section);

class KinematicStage : public Stage {
 public:
  explicit KinematicStage(KinematicStageConfig config = {}) : config_(std::move(config)) {}
  std::string Name() const override { return retarget::kKinematicStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;
  std::optional<StageResult> Redecide(const Json& measurements) const override;

 private:
  struct SceneFiles {
    std::string xml;                    // object scene MJCF, "" without object
    std::filesystem::path dir;          // its folder
    std::filesystem::path robot_scene;  // where to write hand + scene ("" = not written)
  };
  retarget::HandTrajectory RetargetHand(const std::string& hand, const std::string& robots,
                              const std::vector<retarget::Keypoints21>& human, const std::vector<bool>& valid,
                              double fps, const SceneFiles& scene, size_t* compat_changes) const;
  KinematicStageConfig config_;
};

}  // namespace doasido::stages
