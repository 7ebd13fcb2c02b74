#include "retarget/dynamic/bimanual_retarget.h"

#include <tinyxml2.h>

#include "core/error.h"
#include "core/file_text.h"
#include "robot/mjcf_compat.h"
#include "robot/mjcf_text.h"

namespace doasido::retarget {
namespace {

void CheckLeftHand(const recon::Reconstruction& r, const std::string& label) {
  int seen = 0;
  for (size_t t = 0; t < r.left_valid.size(); ++t) {
    if (!r.left_valid[t]) continue;
    if (!r.left_joints[t].allFinite()) {
      throw Error("bad_reference", "non-finite values in frame " + std::to_string(t),
                  {.file = label, .field = "left_joints"});
    }
    ++seen;
  }
  if (!seen) throw Error("bad_reference", "no valid left hand frame", {.file = label, .field = "left_valid"});
}


// Mean distance of a hand's simulated wrist from its reference over the
// frames the hand was seen.
double WristError(const HandTrajectory& simulated, const HandTrajectory& kinematic, const std::string& prefix) {
  std::array<int, 3> sim{}, ref{};
  for (int i = 0; i < 3; ++i) {
    const auto find = [&](const HandTrajectory& t, const std::string& name) {
      return static_cast<int>(std::find(t.qpos_names.begin(), t.qpos_names.end(), name) - t.qpos_names.begin());
    };
    sim[i] = find(simulated, prefix + kWristJoints[i]);
    ref[i] = find(kinematic, kWristJoints[i]);
  }
  double sum = 0;
  int n = 0;
  for (size_t t = 0; t < kinematic.qpos.size(); ++t) {
    if (!kinematic.valid[t]) continue;
    Vec3 d;
    for (int i = 0; i < 3; ++i) d[i] = simulated.qpos[t][sim[i]] - kinematic.qpos[t][ref[i]];
    sum += d.norm();
    ++n;
  }
  return n ? sum / n : 0.0;
}

}  // namespace

BimanualRetarget::BimanualRetarget(const recon::Reconstruction& r, const TriMesh& mesh, const Embodiment& left,
                                   const Embodiment& right, const DynamicRetargetConfig& config,
                                   const std::filesystem::path& scene_dir, const std::string& label)
    : clip_{r, mesh, label, {}} {
  try {
    CheckReference(r, label);
    CheckLeftHand(r, label);
    clip_.object = FilledObjectPoses(r);
    SceneConfig scene_config = config.scene;
    scene_config.place_on_floor = false;
    const ObjectScene scene = BuildObjectScene(mesh, clip_.object[0], scene_config, scene_dir);
    const std::string scene_xml = ReadFileOrThrow(scene.xml_path, "io", "cannot read the scene");

    // Step 3: each hand alone with the object.
    const auto kinematic = [&](const Embodiment& e, const std::vector<recon::Joints21>& joints,
                               const std::vector<bool>& valid) {
      const HandModel model = BuildHandModel(e, scene_xml, scene_dir);
      KinematicRetargeter retargeter(model, config.kinematic);
      HandTrajectory t = retargeter.Solve(joints, valid, r.fps, {}, &clip_.object);
      t.object_poses = clip_.object;
      return t;
    };
    left_kinematic_ = kinematic(left, r.left_joints, r.left_valid);
    right_kinematic_ = kinematic(right, r.right_joints, r.right_valid);

    // Step 4: both hands and the object in one model.
    tinyxml2::XMLDocument doc;
    ParseMjcfText(PrefixMjcfNames(BuildHandModel(right).xml, kRightPrefix, right.name), right.name, doc);
    AppendRootChildren(doc, PrefixMjcfNames(BuildHandModel(left).xml, kLeftPrefix, left.name), left.name);
    AppendRootChildren(doc, PrepareMjcfText(scene_xml, scene_dir, (scene_dir / "scene").string()).xml, "scene");
    robot_scene_xml_ = PrintMjcf(doc);
    model_ = CompileMjcfText(robot_scene_xml_, label);
  } catch (const Error& e) {
    throw NamingClip(e, label);
  }
}

BimanualRun BimanualRetarget::Track(const AnnealedSamplerConfig& sampler,
                                    const std::function<void(int, int)>& progress) const {
  BimanualRun run;
  run.left_kinematic = left_kinematic_;
  run.right_kinematic = right_kinematic_;
  run.robot_scene_xml = robot_scene_xml_;
  const mjModel* m = model_.get();
  const recon::Reconstruction& r = clip_.r;
  try {
    const HandTrajectory both = CombineBimanualTrajectories(run.left_kinematic, run.right_kinematic);
    const double epsilon = sampler.reward.transition_epsilon;
    const std::vector<Pose>& object = clip_.object;
    const std::vector<bool> in_left = LabelInHand(r.left_joints, r.left_valid, object, clip_.mesh, epsilon);
    const std::vector<bool> in_right = LabelInHand(r.right_joints, r.right_valid, object, clip_.mesh, epsilon);
    // Step 5: the transition reward asks each hand for its own contact.
    const SceneIndex index = IndexScene(m);
    const auto bit = [&](const std::string& prefix) {
      for (size_t h = 0; h < index.hands.size(); ++h) {
        if (index.hands[h].rfind(prefix, 0) == 0) return static_cast<uint8_t>(1u << h);
      }
      throw Error("bad_mjcf", "no wrist mount named " + prefix + kWristMountBody, {.clip = clip_.label});
    };
    const uint8_t left_bit = bit(kLeftPrefix), right_bit = bit(kRightPrefix);
    const std::vector<bool> resting = LabelResting(object, clip_.mesh, sampler.reward.transition_rest_height);
    std::vector<uint8_t> in_hand(in_left.size());
    for (size_t t = 0; t < in_hand.size(); ++t) {
      in_hand[t] = (in_left[t] ? left_bit : 0) | (in_right[t] ? right_bit : 0);
      run.left_in_hand_frames += in_left[t] && !resting[t];
      run.right_in_hand_frames += in_right[t] && !resting[t];
    }
    const DynamicReference ref = BuildReference(m, both, object, in_hand, resting, WarmupSeconds(sampler));
    const DynamicResult result = RetargetDynamics(m, ref, sampler, progress);
    run.stats = result.stats;
    run.trajectory = SimulatedTrajectory(m, index, ref, result, both);
    run.metrics = ObjectMetrics(clip_, run.trajectory);
    run.left_wrist_error = WristError(run.trajectory, run.left_kinematic, kLeftPrefix);
    run.right_wrist_error = WristError(run.trajectory, run.right_kinematic, kRightPrefix);
  } catch (const Error& e) {
    throw NamingClip(e, clip_.label);
  }
  run.trajectory.metrics = {{kMetricPositionError, run.metrics.e_pos},
                            {kMetricRotationError, run.metrics.e_rot},
                            {kMetricSuccess, run.metrics.success},
                            {"frames", run.metrics.frames},
                            {"left_wrist_error", run.left_wrist_error},
                            {"right_wrist_error", run.right_wrist_error}};
  return run;
}

BimanualRun RetargetBimanual(const recon::Reconstruction& r, const TriMesh& mesh, const Embodiment& left,
                             const Embodiment& right, const DynamicRetargetConfig& config,
                             const std::filesystem::path& scene_dir, const std::string& label,
                             const std::function<void(int, int)>& progress) {
  const BimanualRetarget clip(r, mesh, left, right, config, scene_dir, label);
  return clip.Track(EffectiveSampler(config), progress);
}

}  // namespace doasido::retarget
