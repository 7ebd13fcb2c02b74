#include "retarget/kinematic_stage.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>

#include <spdlog/spdlog.h>

#include "core/data_dirs.h"
#include "core/error.h"
#include "core/file_text.h"
#include "recon/bundle.h"
#include "recon/bundle_location.h"
#include "recon/gravity.h"
#include "recon/recon_stage.h"
#include "recon/reconstruction.h"
#include "retarget/embodiment.h"

namespace doasido::retarget {
namespace {

// What the stage retargets: hand keypoints and object poses in the world
// frame (z up, floor z = 0), the object mesh, the frame rate.
struct StageInput {
  std::string source;  // folder read
  std::vector<Keypoints21> human;
  std::vector<bool> valid;
  std::vector<Pose> object_world;
  std::optional<TriMesh> object_mesh;
  double fps = 30;
  bool has_right_hand = false;
};

// From the recon stage's artifact: already metric and gravity-aligned.
StageInput FromReconstruction(const std::filesystem::path& dir) {
  const recon::Reconstruction r = recon::ReadReconstruction(dir);
  StageInput in;
  in.source = dir.string();
  in.fps = r.fps;
  in.valid = r.right_valid;
  for (const auto& j : r.right_joints) in.human.push_back(j);
  in.has_right_hand = std::any_of(r.right_valid.begin(), r.right_valid.end(), [](bool v) { return v; });
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
  if (!bundle.hand_right || bundle.hand_right->joints.empty()) return in;
  in.has_right_hand = true;
  const recon::HandTrack& hand = *bundle.hand_right;
  const size_t frames = hand.joints.size();
  Vec3 up(0, -1, 0);
  if (!bundle.gravity_up.empty()) {
    Vec3 sum = Vec3::Zero();
    for (const Vec3& g : bundle.gravity_up) sum += g;
    if (sum.norm() > 1e-9) up = sum.normalized();
  }
  const Mat3 r = recon::UpToZ(up);
  in.human.resize(frames);
  in.valid.resize(frames);
  for (size_t t = 0; t < frames; ++t) {
    in.valid[t] = t < hand.valid.size() ? static_cast<bool>(hand.valid[t]) : true;
    in.human[t] = (hand.joints[t] * r.transpose()).eval();
  }
  for (const Pose& p : bundle.object_poses) in.object_world.push_back({Quat(r) * p.q, r * p.t});
  double floor_z = 1e30;
  if (bundle.object_mesh && !in.object_world.empty()) {
    for (int v = 0; v < bundle.object_mesh->num_vertices(); ++v) {
      floor_z = std::min(floor_z, (in.object_world[0] * Vec3(bundle.object_mesh->vertices.row(v).transpose())).z());
    }
  } else {
    for (size_t t = 0; t < frames; ++t) {
      if (in.valid[t]) floor_z = std::min(floor_z, in.human[t].col(2).minCoeff() - 0.05);
    }
  }
  if (floor_z > 1e29) floor_z = 0;
  for (auto& k : in.human) k.col(2).array() -= floor_z;
  for (auto& p : in.object_world) p.t.z() -= floor_z;
  return in;
}

// The recon artifact when the recon stage ran, else the bundle.
StageInput LoadInput(const ClipContext& context, const std::string& clip) {
  try {
    const auto recon_dir = recon::SiblingArtifactDir(context, recon::kReconStageName);
    if (std::filesystem::is_regular_file(recon_dir / recon::kReconstructionNpz)) {
      return FromReconstruction(recon_dir);
    }
    const std::filesystem::path dir = recon::BundleDir(context);
    return FromBundle(recon::ReadBundle(dir), dir);
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.clip = clip;
    throw Error(e.code(), e.message(), site);
  }
}

}  // namespace

std::string DefaultRobotsDir() {
  const std::filesystem::path p = DataDir("robots", "DOASIDO_ROBOTS_DIR");
  return std::filesystem::exists(p) ? std::filesystem::weakly_canonical(p).string() : std::string();
}

StageResult KinematicStage::Run(const ClipContext& context) {
  const std::string clip = context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                                            : context.clip.external_id;
  const StageInput in = LoadInput(context, clip);
  StageResult result;
  if (!in.has_right_hand) {
    result.verdict = Verdict::kReject;
    result.reason = "no_right_hand";
    result.measurements["bundle"] = in.source;
    return result;
  }
  const std::vector<Keypoints21>& human = in.human;
  const std::vector<bool>& valid = in.valid;
  const std::vector<Pose>& object_world = in.object_world;
  const size_t frames = human.size();

  const std::string robots = config_.robots_dir.empty() ? DefaultRobotsDir() : config_.robots_dir;
  std::filesystem::create_directories(context.artifact_dir);
  std::string scene_xml;
  std::filesystem::path scene_dir;
  if (in.object_mesh && !object_world.empty()) {
    scene_dir = context.artifact_dir / "scene";
    SceneConfig scene_config = config_.scene;
    scene_config.place_on_floor = false;  // the floor is already under the object
    const ObjectScene scene = BuildObjectScene(*in.object_mesh, object_world[0], scene_config, scene_dir);
    scene_xml = TryReadFile(scene.xml_path).value_or("");
    result.measurements["object_mass"] = scene.mass;
    result.measurements["object_hulls"] = scene.hull_files.size();
    result.artifacts.emplace_back("scene", "scene/scene.xml");
  }
  const HandModel model = BuildHandModel(FindEmbodiment(config_.hand, robots), scene_xml, scene_dir);
  if (!scene_xml.empty()) {
    std::ofstream out(context.artifact_dir / "robot_scene.xml");
    out << model.xml;
    result.artifacts.emplace_back("robot_scene", "robot_scene.xml");
  }
  KinematicRetargeter solver(model, config_.kinematic);
  HandTrajectory trajectory = solver.Solve(human, valid, in.fps);
  trajectory.object_poses = object_world;
  WriteTrajectoryJson(trajectory, context.artifact_dir / "trajectory.json");
  WriteTrajectoryCsv(trajectory, context.artifact_dir / "trajectory.csv");
  result.artifacts.emplace_back("trajectory", "trajectory.json");
  result.artifacts.emplace_back("trajectory_csv", "trajectory.csv");

  const FingertipErrorStats error = SummarizeFingertipError(trajectory.fingertip_error);
  Json& m = result.measurements;
  m["bundle"] = in.source;
  m["embodiment"] = trajectory.embodiment;
  m["frames"] = frames;
  m["valid_frames"] = error.frames;
  m["scale"] = trajectory.scale;
  m["fingertip_error_mean"] = error.mean;
  m["fingertip_error_p95"] = error.p95;
  m["compat_changes"] = model.changes.size();
  if (auto redecided = Redecide(m)) {
    result.verdict = redecided->verdict;
    result.reason = redecided->reason;
  }
  spdlog::info("{} {}: {} frames, scale {:.3f}, fingertip error {:.1f} mm", kKinematicStageName, clip,
               frames, trajectory.scale, 1000 * m["fingertip_error_mean"].get<double>());
  return result;
}

std::optional<StageResult> KinematicStage::Redecide(const Json& measurements) const {
  if (!measurements.contains("fingertip_error_mean")) return std::nullopt;
  StageResult r;
  r.measurements = measurements;
  if (measurements["fingertip_error_mean"].get<double>() > config_.flag_fingertip_error) {
    r.verdict = Verdict::kFlag;
    r.reason = "kinematic_error";
  }
  return r;
}

}  // namespace doasido::retarget
