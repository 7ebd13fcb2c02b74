// The retarget_kinematic stage on a synthetic clip bundle: a right hand made
// by forward kinematics of the Sharpa hand (so the answer is known), seen
// from a camera (y down), and a box-shaped object resting under it.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "recon/bundle/bundle.h"
#include "recon/align/gravity.h"
#include "recon/reconstruction.h"
#include "retarget/kinematic/kinematic_retarget.h"
#include "stages/kinematic_stage.h"
#include "robot/embodiment.h"
#include "tests/test_util.h"

namespace doasido::retarget {
namespace {

using doasido::testing::SharedData;
using doasido::testing::TempDir;

TriMesh Box(double hx, double hy, double hz) {
  TriMesh m;
  m.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) {
    m.vertices.row(i) << ((i & 1) ? hx : -hx), ((i >> 1 & 1) ? hy : -hy), ((i >> 2 & 1) ? hz : -hz);
  }
  m.faces.resize(12, 3);
  m.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4,
      6, 1, 3, 5, 3, 7, 5;
  return m;
}

TEST(KinematicStage, RetargetsASyntheticBundle) {
  const HandModel hand = BuildHandModel(FindEmbodiment("sharpa_right", SharedData() / "robots"));
  KinematicRetargeter fk(hand);
  const mjModel* m = hand.model.get();
  // A known 12-frame motion: fingers sweep from open to half closed while
  // the wrist moves 5 cm.
  const int frames = 12;
  std::vector<recon::Joints21> joints;
  const Mat3 world_to_camera = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();
  for (int t = 0; t < frames; ++t) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(6 + hand.finger_qpos.size());
    q.head<3>() = Vec3(0.05 * t / frames, 0.0, 0.15);
    q[4] = 0.3;
    for (size_t k = 0; k < hand.finger_qpos.size(); ++k) {
      int j = 0;
      while (m->jnt_qposadr[j] != hand.finger_qpos[k]) ++j;
      const double lo = m->jnt_range[2 * j], hi = m->jnt_range[2 * j + 1];
      q[6 + k] = std::clamp(0.5 * (lo + hi) * t / frames, lo, hi);
    }
    const std::vector<Vec3> x = fk.Points(q);
    recon::Joints21 k = recon::Joints21::Zero();
    for (size_t i = 0; i < hand.points.size(); ++i) {
      k.row(hand.points[i].keypoint) = (world_to_camera * x[i] + Vec3(0, 0, 0.6)).transpose();
    }
    k.row(1) = 0.5 * (k.row(0) + k.row(2));  // unmapped thumb CMC
    joints.push_back(k);
  }
  recon::ClipBundle bundle;
  bundle.width = 640;
  bundle.height = 480;
  bundle.frames = frames;
  bundle.fps = 30;
  bundle.K = {Mat3::Identity()};
  recon::HandTrack right;
  right.valid.assign(frames, true);
  right.joints = joints;
  bundle.hand_right = right;
  bundle.object_mesh = Box(0.03, 0.03, 0.03);
  for (int t = 0; t < frames; ++t) {
    bundle.object_poses.push_back({Quat(world_to_camera), world_to_camera * Vec3(0.1, 0, 0.03) + Vec3(0, 0, 0.6)});
  }
  TempDir root;
  recon::WriteBundle(bundle, root / "artifacts/7/bundle");

  ClipContext context;
  context.clip.id = 7;
  context.clip.external_id = "synthetic";
  context.artifact_dir = root / "artifacts/7/retarget_kinematic";
  stages::KinematicStageConfig config;
  config.robots_dir = (SharedData() / "robots").string();
  stages::KinematicStage stage(config);
  const StageResult result = stage.Run(context);
  EXPECT_EQ(result.verdict, Verdict::kPass) << result.reason;
  EXPECT_EQ(result.measurements["frames"], frames);
  EXPECT_NEAR(result.measurements["scale"].get<double>(), 1.0, 1e-3);
  EXPECT_LT(result.measurements["fingertip_error_mean"].get<double>(), 0.002);

  const HandTrajectory t = ReadTrajectoryJson(context.artifact_dir / "trajectory.json");
  ASSERT_EQ(t.qpos.size(), static_cast<size_t>(frames));
  ASSERT_EQ(t.object_poses.size(), static_cast<size_t>(frames));
  // World frame: up is +z and the floor touches the box's bottom.
  EXPECT_NEAR(t.object_poses[0].t.z(), 0.03, 1e-9);
  EXPECT_TRUE(std::filesystem::exists(context.artifact_dir / "scene/scene.xml"));
  EXPECT_TRUE(std::filesystem::exists(context.artifact_dir / "robot_scene.xml"));
  EXPECT_TRUE(std::filesystem::exists(context.artifact_dir / "trajectory.csv"));

  // Once the recon stage has written its artifact, that is what is read:
  // the same hand, already in a world frame, and the box resting higher.
  recon::Reconstruction rec;
  rec.fps = 30;
  const Mat3 to_world = recon::UpToZ(Vec3(0, -1, 0));
  for (int f = 0; f < frames; ++f) {
    rec.right_valid.push_back(true);
    rec.right_joints.push_back((joints[f] * to_world.transpose()).eval());
    rec.object_valid.push_back(true);
    rec.object_poses.push_back({Quat::Identity(), Vec3(0.1, 0.2, 0.05)});
  }
  SaveObj(*bundle.object_mesh, root / "box.obj");
  rec.object_mesh = root / "box.obj";
  recon::WriteReconstruction(rec, root / "artifacts/7/recon");
  const StageResult from_recon = stage.Run(context);
  EXPECT_EQ(from_recon.measurements["bundle"], (root / "artifacts/7/recon").string());
  EXPECT_LT(from_recon.measurements["fingertip_error_mean"].get<double>(), 0.002);
  EXPECT_NEAR(ReadTrajectoryJson(context.artifact_dir / "trajectory.json").object_poses[0].t.z(),
              0.05, 1e-9);
  std::filesystem::remove_all(root / "artifacts/7/recon");

  // Re-thresholding flags the clip without running it again.
  stages::KinematicStageConfig strict = config;
  strict.flag_fingertip_error = -1.0;  // every error is above it
  const auto flagged = stages::KinematicStage(strict).Redecide(result.measurements);
  ASSERT_TRUE(flagged);
  EXPECT_EQ(flagged->verdict, Verdict::kFlag);
}

TEST(KinematicStage, MissingBundleNamesTheClip) {
  TempDir root;
  ClipContext context;
  context.clip.external_id = "clip42";
  context.artifact_dir = root / "artifacts/42/retarget_kinematic";
  stages::KinematicStage stage;
  try {
    stage.Run(context);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.site().clip, "clip42");
  }
}

}  // namespace
}  // namespace doasido::retarget
