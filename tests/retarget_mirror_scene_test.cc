// A lone left hand with its object, mirrored onto the right robot hand
// (retarget/mirror_scene.h): against the reflection S = diag(-1, 1, 1)
// applied to the world directly. Every world point of the mirrored object
// is S times the original's, the mesh stays closed and outward (same
// positive volume), the hand keeps its distance to the object's surface in
// every frame (it still holds it), and mirroring twice gives the original.
#include <gtest/gtest.h>

#include <random>

#include "retarget/mirror_scene.h"
#include "synth/objects.h"

namespace doasido::retarget {
namespace {

const Eigen::Matrix3d kS = Eigen::Vector3d(-1, 1, 1).asDiagonal();

Pose RandomPose(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  Pose p;
  p.q = Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
  p.t = Vec3(n(rng), n(rng), n(rng)) * 0.3;
  return p;
}

TEST(MirrorScene, MirroredObjectIsTheWorldsReflection) {
  // The mug: its handle on +x makes it its own mirror image nowhere.
  const TriMesh mug = synth::MakeMug(0.04, 0.1);
  const TriMesh mirrored = MirrorMesh(mug);
  EXPECT_GT(mug.Volume(), 0);
  EXPECT_NEAR(mirrored.Volume(), mug.Volume(), 1e-12);  // faces still outward
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const Pose pose = RandomPose(rng);
    const Pose mirrored_pose = MirrorPose(pose);
    EXPECT_NEAR(mirrored_pose.q.norm(), 1, 1e-12);
    EXPECT_NEAR(mirrored_pose.R().determinant(), 1, 1e-12);  // a rotation, not a reflection
    for (int v = 0; v < mug.num_vertices(); ++v) {
      const Vec3 world = pose * Vec3(mug.vertices.row(v).transpose());
      const Vec3 got = mirrored_pose * Vec3(mirrored.vertices.row(v).transpose());
      ASSERT_LT((got - kS * world).norm(), 1e-12) << "vertex " << v;
    }
  }
  // Twice is the original.
  const TriMesh back = MirrorMesh(mirrored);
  EXPECT_EQ(back.vertices, mug.vertices);
  EXPECT_EQ(back.faces, mug.faces);
  const Pose p = RandomPose(rng);
  EXPECT_LT((MirrorPose(MirrorPose(p)).t - p.t).norm(), 1e-15);
  EXPECT_LT(MirrorPose(MirrorPose(p)).q.angularDistance(p.q), 1e-12);
}

TEST(MirrorScene, LeftHandOntoRightKeepsItsGripOnTheObject) {
  const TriMesh mug = synth::MakeMug(0.04, 0.1);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n(0, 0.05);
  recon::Reconstruction r;
  const int frames = 6;
  for (int t = 0; t < frames; ++t) {
    const Pose object = RandomPose(rng);
    Keypoints21 left;
    for (int j = 0; j < 21; ++j) left.row(j) = (object * Vec3(n(rng), n(rng), 0.05 + n(rng))).transpose();
    r.left_joints.push_back(left);
    r.left_valid.push_back(t != 2);
    r.right_joints.push_back(Keypoints21::Constant(std::nan("")));
    r.right_valid.push_back(false);
    r.object_poses.push_back(object);
    r.object_valid.push_back(true);
  }
  const recon::Reconstruction m = MirrorLeftOntoRight(r);
  const TriMesh mirrored = MirrorMesh(mug);
  EXPECT_TRUE(m.left_joints.empty());
  EXPECT_TRUE(m.left_valid.empty());
  EXPECT_EQ(m.right_valid, r.left_valid);
  ASSERT_EQ(m.frames(), frames);
  for (int t = 0; t < frames; ++t) {
    for (int j = 0; j < 21; ++j) {
      const Vec3 original = r.left_joints[t].row(j).transpose();
      const Vec3 now = m.right_joints[t].row(j).transpose();
      EXPECT_LT((now - kS * original).norm(), 1e-15);
      // The same distance to the surface, in each one's object frame.
      const double before = synth::DistanceToMesh(mug, r.object_poses[t].Inverse() * original);
      const double after = synth::DistanceToMesh(mirrored, m.object_poses[t].Inverse() * now);
      EXPECT_NEAR(after, before, 1e-9) << "frame " << t << " joint " << j;
    }
  }
}

}  // namespace
}  // namespace doasido::retarget
