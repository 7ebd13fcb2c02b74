// Which of two hands holds the object (retarget/holding_hand.h): a cylinder
// at the origin, one hand's fingertips on its side, the other hand 30 cm
// away; the answer follows the hand that touches, whichever side it is, and
// a reconstruction without a left hand or object is never "left".
#include "retarget/holding_hand.h"

#include <gtest/gtest.h>

#include "synth/objects.h"

namespace doasido::retarget {
namespace {

// A hand whose joints all sit at `at` (world frame) on every frame.
std::vector<recon::Joints21> HandAt(const Vec3& at, int frames) {
  recon::Joints21 j;
  for (int k = 0; k < 21; ++k) j.row(k) = at.transpose();
  return std::vector<recon::Joints21>(frames, j);
}

recon::Reconstruction Scene(const Vec3& left_at, const Vec3& right_at) {
  const int T = 10;
  recon::Reconstruction r;
  r.fps = 30;
  r.object_valid.assign(T, true);
  r.object_poses.assign(T, Pose{});
  r.left_valid.assign(T, true);
  r.right_valid.assign(T, true);
  r.left_joints = HandAt(left_at, T);
  r.right_joints = HandAt(right_at, T);
  return r;
}

TEST(HoldingHand, TheHandOnTheObjectIsTheOneThatHoldsIt) {
  const TriMesh cup = synth::MakeCylinder(0.04, 0.12, 24);
  const Vec3 on_side(0.041, 0, 0.06), away(0.34, 0, 0.06);
  EXPECT_TRUE(LeftHandHoldsObject(Scene(on_side, away), cup));
  EXPECT_FALSE(LeftHandHoldsObject(Scene(away, on_side), cup));
  // The left hand touches only while the right is not seen: still the left.
  recon::Reconstruction r = Scene(on_side, away);
  for (int t = 0; t < 5; ++t) r.right_valid[t] = false;
  EXPECT_TRUE(LeftHandHoldsObject(r, cup));
  // No left hand, or no object: never the left.
  recon::Reconstruction right_only = Scene(on_side, away);
  right_only.left_valid.clear();
  EXPECT_FALSE(LeftHandHoldsObject(right_only, cup));
  EXPECT_FALSE(LeftHandHoldsObject(Scene(on_side, away), TriMesh{}));
  const recon::Reconstruction kept = KeepOnlyLeftHand(Scene(on_side, away));
  EXPECT_EQ(kept.right_valid, std::vector<bool>(10, false));
  EXPECT_EQ(kept.left_valid, std::vector<bool>(10, true));
}

}  // namespace
}  // namespace doasido::retarget
