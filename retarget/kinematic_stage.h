// The `retarget_kinematic` queue stage: a clip's reconstructed right hand
// (and object) become the reference robot trajectory and the simulation
// scene the dynamics-aware optimiser starts from (seed section 3.2).
//
// Input: the `recon` stage's artifact <artifacts>/<clip>/recon/
// (recon/reconstruction.h: metric, gravity-aligned right hand and object;
// frames without an object pose hold the previous one) when it exists, else
// the clip bundle (recon/bundle_location.h BundleDir) as before: hands.npz
// right hand, object/poses.npz, object/mesh.obj, gravity.npz, meta.json fps,
// put in a world frame whose +z is up (mean of gravity.npz, else the
// camera's -y) with the floor z = 0 touching the object's lowest point in
// the first frame (or 5 cm below the lowest hand keypoint without object).
//
// Output in artifact_dir: trajectory.json and trajectory.csv
// (kinematic_retarget.h HandTrajectory: robot qpos per frame, object poses
// in the world frame), and with an object scene/scene.xml + hull OBJs
// (scene_builder.h) and robot_scene.xml (hand with floating wrist + scene).
// Verdict: pass, or flag ("kinematic_error") when the mean fingertip error
// exceeds flag_fingertip_error; reject ("no_right_hand") without a right hand.
#pragma once

#include <string>

#include "core/config.h"
#include "db/stage.h"
#include "retarget/config_checks.h"
#include "retarget/kinematic_retarget.h"
#include "retarget/scene_builder.h"

namespace doasido::retarget {

// The stage's name: its queue name, its config section and its artifact folder.
inline constexpr const char* kKinematicStageName = "retarget_kinematic";

struct KinematicStageConfig {
  std::string hand = "sharpa_right";  // embodiment name or description path
  std::string robots_dir;             // folder of descriptions; "" = DefaultRobotsDir()
  double flag_fingertip_error = 0.02; // m, mean over frames
  KinematicConfig kinematic;
  SceneConfig scene;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(KinematicStageConfig, hand, robots_dir,
                                                flag_fingertip_error, kinematic, scene)
// Also checks the nested kinematic and scene tables (retarget/config_checks.h).
void CheckConfig(const KinematicStageConfig& c, const std::string& section);

// The folder of third-party robot models and descriptions: $DOASIDO_ROBOTS_DIR,
// else share/doasido/robots beside the executable's folder (the build links
// it to ../shared/data/robots when that exists), when it exists; else "".
std::string DefaultRobotsDir();

class KinematicStage : public Stage {
 public:
  explicit KinematicStage(KinematicStageConfig config = {}) : config_(std::move(config)) {}
  std::string Name() const override { return kKinematicStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;
  std::optional<StageResult> Redecide(const Json& measurements) const override;

 private:
  KinematicStageConfig config_;
};

}  // namespace doasido::retarget
