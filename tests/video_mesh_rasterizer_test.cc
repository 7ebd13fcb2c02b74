// The one rasteriser (video/mesh_rasterizer.h): the same coverage and depth
// as a brute-force reference on a posed hand and a sphere, and exact depth
// of a plane that passes behind the camera (near-plane clipping). The meshes
// are synth's.
#include "video/mesh_rasterizer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "synth/hand_model.h"
#include "synth/objects.h"

namespace doasido::video {
namespace {

using synth::HandFrame;
using synth::HandPose;
using synth::MakePlane;
using synth::MakeSphere;
using synth::PoseHand;
using synth::RelaxedPose;
using synth::Side;

TEST(Rasterizer, MatchesBruteForceReference) {
  const Camera cam{96, 72, 80, 80, 47.5, 35.5};
  HandPose pose =
      RelaxedPose(Pose{Quat(HandFrame(Vec3(0, -1, 0), Vec3(0, 0, -1))), Vec3(0.0, 0.06, 0.35)});
  const TriMesh hand = PoseHand(pose, Side::kRight).mesh;
  const TriMesh sphere = MakeSphere(0.04).Transformed(Pose{Quat::Identity(), Vec3(0.03, 0, 0.3)});
  RasterTarget fast, slow;
  fast.Reset(cam.width, cam.height);
  slow.Reset(cam.width, cam.height);
  Rasterize(sphere, cam, 3, fast);
  Rasterize(hand, cam, 5, fast);
  RasterizeBruteForce(sphere, cam, 3, slow);
  RasterizeBruteForce(hand, cam, 5, slow);
  int covered = 0, same_surface = 0;
  double max_dz = 0;
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const std::uint8_t a = fast.surface.at<std::uint8_t>(y, x),
                         b = slow.surface.at<std::uint8_t>(y, x);
      if (a == 0 && b == 0) continue;
      ++covered;
      same_surface += a == b;
      if (a == b)
        max_dz = std::max<double>(
            max_dz, std::abs(fast.depth.at<float>(y, x) - slow.depth.at<float>(y, x)));
    }
  }
  EXPECT_GT(covered, 500);
  EXPECT_GE(same_surface, covered - 2);  // ties on shared edges may differ
  EXPECT_LT(max_dz, 1e-5);
}

TEST(Rasterizer, DepthOfAPlaneIsExactAndNearClippingWorks) {
  const Camera cam{64, 48, 50, 50, 31.5, 23.5};
  // A huge tilted plane passing behind the camera: z = 0.5 + 0.5 y.
  TriMesh plane = MakePlane(20, 20);
  const Quat tilt(Eigen::AngleAxisd(std::atan(0.5), Vec3::UnitX()));
  plane = plane.Transformed(Pose{tilt, Vec3(0, 0, 0.5)});
  RasterTarget t;
  t.Reset(cam.width, cam.height);
  Rasterize(plane, cam, 1, t);
  for (int y = 0; y < cam.height; y += 3) {
    for (int x = 0; x < cam.width; x += 3) {
      // Ray (u, v) hits z = 0.5 + 0.5 * (v - cy) / f * z.
      const double k = (y - cam.cy) / cam.fy;
      const double z = 0.5 / (1 - 0.5 * k);
      if (z <= 0.01 || z > 100) continue;
      ASSERT_EQ(t.surface.at<std::uint8_t>(y, x), 1) << x << "," << y;
      EXPECT_NEAR(t.depth.at<float>(y, x), z, 1e-5 * z);
    }
  }
}

}  // namespace
}  // namespace doasido::video
