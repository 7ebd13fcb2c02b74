#include "stages/kinematic_stage.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>

#include <spdlog/spdlog.h>

#include "core/config_check.h"
#include "core/data_dirs.h"
#include "core/error.h"
#include "core/file_text.h"
#include "recon/bundle/bundle.h"
#include "stages/clip_inputs.h"
#include "recon/align/gravity.h"
#include "stages/recon_stage.h"
#include "recon/reconstruction.h"
#include "stages/dynamic_stage.h"
#include "retarget/mirror_scene.h"
#include "robot/embodiment.h"

namespace doasido::stages {

using namespace retarget;  // the algorithms this stage runs
namespace {

// What the stage retargets: hand keypoints and object poses in the world
// frame (z up, floor z = 0), the object mesh, the frame rate.
struct StageInput {
  std::string source;  // folder read
  std::vector<Keypoints21> human;
  std::vector<bool> valid;
  std::vector<Keypoints21> left;        // the left hand the same way; empty without one
  std::vector<bool> left_valid;
  std::vector<Pose> object_world;
  std::optional<TriMesh> object_mesh;
  double fps = 30;
  bool has_right_hand = false;
  bool has_left_hand = false;
};

bool Any(const std::vector<bool>& v) { return std::any_of(v.begin(), v.end(), [](bool b) { return b; }); }

// From the recon stage's artifact: already metric and gravity-aligned.
StageInput FromReconstruction(const std::filesystem::path& dir) {
  const recon::Reconstruction r = recon::ReadReconstruction(dir);
  StageInput in;
  in.source = dir.string();
  in.fps = r.fps;
  in.valid = r.right_valid;
  for (const auto& j : r.right_joints) in.human.push_back(j);
  in.has_right_hand = Any(r.right_valid);
  in.left_valid = r.left_valid;
  for (const auto& j : r.left_joints) in.left.push_back(j);
  in.has_left_hand = Any(r.left_valid);
  if (!r.object_mesh.empty()) in.object_mesh = LoadMesh(r.object_mesh);
  const bool any_object = std::any_of(r.object_valid.begin(), r.object_valid.end(), [](bool v) { return v; });
  if (any_object) {
    // Frames without a pose hold the nearest earlier one (else the first known).
    int first = 0;
    while (!r.object_valid[first]) ++first;
    Pose last = r.object_poses[first];
    for (int t = 0; t < r.frames(); ++t) {
      if (r.object_valid[t]) last = r.object_poses[t];
      in.object_world.push_back(last);
    }
  }
  return in;
}

// From the raw bundle: camera frame rotated so that up (mean of
// gravity.npz, else the camera's -y) is +z, shifted so the floor z = 0
// touches the object's lowest point in the first frame (or lies 5 cm below
// the lowest hand keypoint when there is no object).
StageInput FromBundle(const recon::ClipBundle& bundle, const std::filesystem::path& dir) {
  StageInput in;
  in.source = dir.string();
  in.fps = bundle.fps > 0 ? bundle.fps : 30.0;
  in.object_mesh = bundle.object_mesh;
  Vec3 up(0, -1, 0);
  if (!bundle.gravity_up.empty()) {
    Vec3 sum = Vec3::Zero();
    for (const Vec3& g : bundle.gravity_up) sum += g;
    if (sum.norm() > 1e-9) up = sum.normalized();
  }
  const Mat3 r = recon::UpToZ(up);
  const auto take = [&](const std::optional<recon::HandTrack>& hand, std::vector<Keypoints21>& human,
                        std::vector<bool>& valid) {
    if (!hand || hand->joints.empty()) return false;
    const size_t frames = hand->joints.size();
    human.resize(frames);
    valid.resize(frames);
    for (size_t t = 0; t < frames; ++t) {
      valid[t] = t < hand->valid.size() ? static_cast<bool>(hand->valid[t]) : true;
      human[t] = (hand->joints[t] * r.transpose()).eval();
    }
    return true;
  };
  in.has_right_hand = take(bundle.hand_right, in.human, in.valid) && Any(in.valid);
  in.has_left_hand = take(bundle.hand_left, in.left, in.left_valid) && Any(in.left_valid);
  for (const Pose& p : bundle.object_poses) in.object_world.push_back({Quat(r) * p.q, r * p.t});
  double floor_z = 1e30;
  if (bundle.object_mesh && !in.object_world.empty()) {
    for (int v = 0; v < bundle.object_mesh->num_vertices(); ++v) {
      floor_z = std::min(floor_z, (in.object_world[0] * Vec3(bundle.object_mesh->vertices.row(v).transpose())).z());
    }
  } else {
    for (const auto* hand : {&in.human, &in.left}) {
      const auto& valid = hand == &in.human ? in.valid : in.left_valid;
      for (size_t t = 0; t < hand->size(); ++t) {
        if (valid[t]) floor_z = std::min(floor_z, (*hand)[t].col(2).minCoeff() - recon::kHandOnlyFloorMargin);
      }
    }
  }
  if (floor_z > 1e29) floor_z = 0;
  for (auto& k : in.human) k.col(2).array() -= floor_z;
  for (auto& k : in.left) k.col(2).array() -= floor_z;
  for (auto& p : in.object_world) p.t.z() -= floor_z;
  return in;
}

// The recon artifact when the recon stage ran, else the bundle.
StageInput LoadInput(const ClipContext& context, const std::string& clip) {
  try {
    const auto recon_dir = SiblingArtifactDir(context, recon::kReconStageName);
    if (std::filesystem::is_regular_file(recon_dir / recon::kReconstructionNpz)) {
      return FromReconstruction(recon_dir);
    }
    const ResolvedBundle resolved = LoadClipBundle(context);
    return FromBundle(resolved.bundle, resolved.dir);
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.clip = clip;
    throw Error(e.code(), e.message(), site);
  }
}


}  // namespace

HandTrajectory KinematicStage::RetargetHand(const std::string& hand, const std::string& robots,
                                            const std::vector<Keypoints21>& human,
                                            const std::vector<bool>& valid, double fps,
                                            const SceneFiles& scene, size_t* compat_changes) const {
  const HandModel model = BuildHandModel(FindEmbodiment(hand, robots), scene.xml, scene.dir);
  if (compat_changes) *compat_changes += model.changes.size();
  if (!scene.xml.empty() && !scene.robot_scene.empty()) {
    std::ofstream out(scene.robot_scene);
    out << model.xml;
  }
  KinematicRetargeter solver(model, config_.kinematic);
  return solver.Solve(human, valid, fps);
}

StageResult KinematicStage::Run(const ClipContext& context) {
  const std::string clip = context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                                            : context.clip.external_id;
  const StageInput in = LoadInput(context, clip);
  StageResult result;
  Json& m = result.measurements;
  m["bundle"] = in.source;
  if (!in.has_right_hand && !in.has_left_hand) {
    result.verdict = Verdict::kReject;
    result.reason = kReasonNoHand;
    return result;
  }
  // trajectory.json: the right hand, else the left one mirrored with the
  // whole scene (object mesh and poses, retarget/mirror_scene.h) onto
  // `hand`: one robot for every episode of a dataset.
  const bool mirrored = !in.has_right_hand;
  const std::vector<Keypoints21> human = mirrored ? MirrorKeypoints(in.left) : in.human;
  const std::vector<bool>& valid = mirrored ? in.left_valid : in.valid;
  const std::vector<Pose> object_world = mirrored ? MirrorPoses(in.object_world) : in.object_world;
  std::optional<TriMesh> object_mesh = in.object_mesh;
  if (mirrored && object_mesh) object_mesh = MirrorMesh(*object_mesh);
  const size_t frames = human.size();

  const std::string robots = config_.robots_dir.empty() ? DefaultRobotsDir() : config_.robots_dir;
  std::filesystem::create_directories(context.artifact_dir);
  SceneFiles scene;
  if (object_mesh && !object_world.empty()) {
    scene.dir = context.artifact_dir / kSceneFolder;
    SceneConfig scene_config = config_.scene;
    scene_config.place_on_floor = false;  // the floor is already under the object
    const ObjectScene built = BuildObjectScene(*object_mesh, object_world[0], scene_config, scene.dir);
    scene.xml = TryReadFile(built.xml_path).value_or("");
    m["object_mass"] = built.mass;
    m["object_hulls"] = built.hull_files.size();
    result.artifacts.emplace_back("scene", std::string(kSceneFolder) + "/" + kSceneFile);
  }
  if (!scene.xml.empty()) {
    scene.robot_scene = context.artifact_dir / kRobotSceneFile;
    result.artifacts.emplace_back("robot_scene", kRobotSceneFile);
  }
  size_t changes = 0;
  HandTrajectory trajectory = RetargetHand(config_.hand, robots, human, valid, in.fps, scene, &changes);
  trajectory.object_poses = object_world;
  WriteTrajectoryJson(trajectory, context.artifact_dir / kTrajectoryFile);
  WriteTrajectoryCsv(trajectory, context.artifact_dir / kTrajectoryCsvFile);
  result.artifacts.emplace_back("trajectory", kTrajectoryFile);
  result.artifacts.emplace_back("trajectory_csv", kTrajectoryCsvFile);

  const FingertipErrorStats error = SummarizeFingertipError(trajectory.fingertip_error);
  m[kMeasureRetargetedHand] = mirrored ? kHandLeftMirrored : kHandRight;
  m["embodiment"] = trajectory.embodiment;
  m["frames"] = frames;
  m["valid_frames"] = error.frames;
  m["scale"] = trajectory.scale;
  m["fingertip_error_mean"] = error.mean;
  m["fingertip_error_p95"] = error.p95;
  if (in.has_right_hand && in.has_left_hand && !config_.left_hand.empty()) {
    // The second hand onto its own robot hand, in the same scene.
    SceneFiles left_scene = scene;
    left_scene.robot_scene.clear();
    HandTrajectory left = RetargetHand(config_.left_hand, robots, in.left, in.left_valid, in.fps,
                                       left_scene, &changes);
    left.object_poses = object_world;
    WriteTrajectoryJson(left, context.artifact_dir / kLeftTrajectoryFile);
    result.artifacts.emplace_back("trajectory_left", kLeftTrajectoryFile);
    const FingertipErrorStats left_error = SummarizeFingertipError(left.fingertip_error);
    m["left_embodiment"] = left.embodiment;
    m["left_valid_frames"] = left_error.frames;
    m["left_fingertip_error_mean"] = left_error.mean;
    m["left_fingertip_error_p95"] = left_error.p95;
  }
  m["compat_changes"] = changes;
  if (auto redecided = Redecide(m)) {
    result.verdict = redecided->verdict;
    result.reason = redecided->reason;
  }
  spdlog::info("{} {}: {} frames ({} hand), scale {:.3f}, fingertip error {:.1f} mm", kKinematicStageName,
               clip, frames, m[kMeasureRetargetedHand].get<std::string>(), trajectory.scale,
               1000 * m["fingertip_error_mean"].get<double>());
  return result;
}

std::optional<StageResult> KinematicStage::Redecide(const Json& measurements) const {
  if (!measurements.contains("fingertip_error_mean")) return std::nullopt;
  StageResult r;
  r.measurements = measurements;
  if (measurements["fingertip_error_mean"].get<double>() > config_.flag_fingertip_error) {
    r.verdict = Verdict::kFlag;
    r.reason = kReasonKinematicError;
  }
  return r;
}

void CheckConfig(const KinematicStageConfig& c, const std::string& section) {
  RequireInRange(section, "flag_fingertip_error", c.flag_fingertip_error, 0, 1);  // m
  CheckHandName(c.hand, c.robots_dir, section, "hand");
  CheckConfig(c.kinematic, section + ".kinematic");
  CheckConfig(c.scene, section + ".scene");
}

}  // namespace doasido::stages
