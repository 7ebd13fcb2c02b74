#include "retarget/kinematic_stage.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include <spdlog/spdlog.h>

#include "core/data_dirs.h"
#include "core/error.h"
#include "recon/bundle.h"
#include "retarget/embodiment.h"

namespace doasido::retarget {
namespace {

std::filesystem::path BundleDir(const ClipContext& context) {
  const Json& meta = context.clip.metadata;
  if (meta.is_object() && meta.contains("bundle") && meta["bundle"].is_string()) {
    std::filesystem::path p = meta["bundle"].get<std::string>();
    if (p.is_relative() && !context.clip.source_list.empty()) {
      p = std::filesystem::path(context.clip.source_list).parent_path() / p;
    }
    return p;
  }
  return context.artifact_dir.parent_path() / "bundle";
}

// Rotation taking camera coordinates to a frame whose +z is `up`.
Mat3 UpToZ(const Vec3& up_camera) {
  const Vec3 z = up_camera.normalized();
  Vec3 x = Vec3::UnitX() - z * z.x();  // camera x, made horizontal
  if (x.norm() < 1e-6) x = Vec3::UnitZ() - z * z.z();
  x.normalize();
  const Vec3 y = z.cross(x);
  Mat3 r;
  r.row(0) = x.transpose();
  r.row(1) = y.transpose();
  r.row(2) = z.transpose();
  return r;
}

}  // namespace

std::string DefaultRobotsDir() {
  const std::filesystem::path p = DataDir("robots", "DOASIDO_ROBOTS_DIR");
  return std::filesystem::exists(p) ? std::filesystem::weakly_canonical(p).string() : std::string();
}

StageResult KinematicStage::Run(const ClipContext& context) {
  const std::string clip = context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                                            : context.clip.external_id;
  const std::filesystem::path dir = BundleDir(context);
  recon::ClipBundle bundle;
  try {
    bundle = recon::ReadBundle(dir);
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.clip = clip;
    throw Error(e.code(), e.message(), site);
  }
  StageResult result;
  if (!bundle.hand_right || bundle.hand_right->joints.empty()) {
    result.verdict = Verdict::kReject;
    result.reason = "no_right_hand";
    result.measurements["bundle"] = dir.string();
    return result;
  }
  const recon::HandTrack& hand = *bundle.hand_right;
  const size_t frames = hand.joints.size();

  Vec3 up(0, -1, 0);
  if (!bundle.gravity_up.empty()) {
    Vec3 sum = Vec3::Zero();
    for (const Vec3& g : bundle.gravity_up) sum += g;
    if (sum.norm() > 1e-9) up = sum.normalized();
  }
  const Mat3 r = UpToZ(up);
  std::vector<Keypoints21> human(frames);
  std::vector<bool> valid(frames);
  for (size_t t = 0; t < frames; ++t) {
    valid[t] = t < hand.valid.size() ? static_cast<bool>(hand.valid[t]) : true;
    human[t] = (hand.joints[t] * r.transpose()).eval();
  }
  std::vector<Pose> object_world;
  for (const Pose& p : bundle.object_poses) object_world.push_back({Quat(r) * p.q, r * p.t});

  // Floor height: the object's lowest point at frame 0, else 5 cm below the hand.
  double floor_z = 1e30;
  if (bundle.object_mesh && !object_world.empty()) {
    for (int v = 0; v < bundle.object_mesh->num_vertices(); ++v) {
      floor_z = std::min(floor_z, (object_world[0] * Vec3(bundle.object_mesh->vertices.row(v).transpose())).z());
    }
  } else {
    for (size_t t = 0; t < frames; ++t) {
      if (valid[t]) floor_z = std::min(floor_z, human[t].col(2).minCoeff() - 0.05);
    }
  }
  if (floor_z > 1e29) floor_z = 0;
  for (auto& k : human) k.col(2).array() -= floor_z;
  for (auto& p : object_world) p.t.z() -= floor_z;

  const std::string robots = config_.robots_dir.empty() ? DefaultRobotsDir() : config_.robots_dir;
  std::filesystem::create_directories(context.artifact_dir);
  std::string scene_xml;
  std::filesystem::path scene_dir;
  if (bundle.object_mesh && !object_world.empty()) {
    scene_dir = context.artifact_dir / "scene";
    SceneConfig scene_config = config_.scene;
    scene_config.place_on_floor = false;  // the floor is already under the object
    const ObjectScene scene = BuildObjectScene(*bundle.object_mesh, object_world[0], scene_config, scene_dir);
    std::ifstream in(scene.xml_path);
    scene_xml.assign(std::istreambuf_iterator<char>(in), {});
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
  HandTrajectory trajectory = solver.Solve(human, valid, bundle.fps > 0 ? bundle.fps : 30.0);
  trajectory.object_poses = object_world;
  WriteTrajectoryJson(trajectory, context.artifact_dir / "trajectory.json");
  WriteTrajectoryCsv(trajectory, context.artifact_dir / "trajectory.csv");
  result.artifacts.emplace_back("trajectory", "trajectory.json");
  result.artifacts.emplace_back("trajectory_csv", "trajectory.csv");

  const FingertipErrorStats error = SummarizeFingertipError(trajectory.fingertip_error);
  Json& m = result.measurements;
  m["bundle"] = dir.string();
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
