// Gravity from a synthetic tilted camera over a table, within 2 degrees, by
// both sources: the bundle's (noisy) up vectors and the RANSAC support-plane
// fit of a noisy point map with a hand above the table and a wall behind.
#include "recon/align/gravity.h"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

namespace doasido::recon {
namespace {

constexpr int kW = 160, kH = 120;

double AngleDeg(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / M_PI;
}

// World: table z = 0 (up +z), a wall x = 0.6 rising from it, a hand-sized
// blob 0.12 m above the table. The camera 0.5 m up, pitched down 55 deg and
// rolled 12 deg. Returns the bundle and the true up in the camera frame.
std::pair<ClipBundle, Vec3> TiltedScene(int frames, std::mt19937_64& rng) {
  const Mat3 look = (Eigen::AngleAxisd(12 * M_PI / 180, Vec3::UnitZ()) *
                     Eigen::AngleAxisd(-(90 + 55) * M_PI / 180, Vec3::UnitX()))
                        .toRotationMatrix();  // camera axes in world coordinates
  const Vec3 centre(0, -0.3, 0.5);
  const Mat3 world_to_cam = look.transpose();
  const Vec3 up = world_to_cam * Vec3::UnitZ();
  Camera cam{kW, kH, 140, 140, 80, 60};
  std::normal_distribution<double> noise(0, 0.004);
  std::uniform_real_distribution<double> uni(0, 1);
  ClipBundle b;
  b.width = kW;
  b.height = kH;
  b.frames = frames;
  b.fps = 30;
  b.K = {cam.K()};
  for (int t = 0; t < frames; ++t) {
    cv::Mat points(kH, kW, CV_32FC3), hand = cv::Mat::zeros(kH, kW, CV_8U);
    for (int v = 0; v < kH; ++v) {
      for (int u = 0; u < kW; ++u) {
        const Vec3 d = look * cam.Unproject(u, v, 1);  // world ray
        double s = d.z() < 0 ? -centre.z() / d.z() : 1e9;                // table
        if (d.x() > 0) s = std::min(s, (0.6 - centre.x()) / d.x());       // wall
        const bool is_hand = std::abs(u - 70) < 12 && std::abs(v - 50) < 10;
        if (is_hand) s = std::min(s, (centre.z() - 0.12) / -d.z());
        Vec3 p = world_to_cam * (d * s);
        if (is_hand) hand.at<std::uint8_t>(v, u) = 255;
        p *= 1 + noise(rng);
        if (uni(rng) < 0.05) p *= 0.3 + uni(rng);  // outliers
        points.at<cv::Vec3f>(v, u) = cv::Vec3f(p.x(), p.y(), p.z());
      }
    }
    b.points.push_back(points);
    b.mask_hand_right.push_back(hand);
    // GeoCalib-like: up with about a degree of noise per frame.
    b.gravity_up.push_back((up + Vec3(noise(rng), noise(rng), noise(rng)) * 4).normalized());
  }
  return {b, up};
}

TEST(Gravity, BundleUpVectorsWithinTwoDegrees) {
  std::mt19937_64 rng(3);
  auto [b, up] = TiltedScene(5, rng);
  const GravityEstimate g = EstimateGravity(b, {});
  EXPECT_EQ(g.source, kGravityFromBundle);
  EXPECT_LT(AngleDeg(g.up, up), 2.0);
  EXPECT_GT(g.spread_deg, 0.1);
}

TEST(Gravity, SupportPlaneFitWithinTwoDegrees) {
  std::mt19937_64 rng(4);
  auto [b, up] = TiltedScene(1, rng);
  b.gravity_up.clear();
  const GravityEstimate g = EstimateGravity(b, {});
  EXPECT_EQ(g.source, kGravityFromPlane);
  EXPECT_LT(AngleDeg(g.up, up), 2.0) << g.up.transpose() << " vs " << up.transpose();
  EXPECT_GT(g.inlier_share, 0.3);
  EXPECT_LT(g.inlier_share, 1.0);
  // use_bundle_up = false ignores the vectors even when present.
  auto [b2, up2] = TiltedScene(1, rng);
  GravityConfig c;
  c.use_bundle_up = false;
  EXPECT_EQ(EstimateGravity(b2, c).source, kGravityFromPlane);
}

TEST(Gravity, UpToZMakesUpTheZAxisAndKeepsCameraXHorizontal) {
  const Vec3 up = Vec3(0.1, -0.9, -0.3).normalized();
  const Mat3 r = UpToZ(up);
  EXPECT_LT((r * up - Vec3::UnitZ()).norm(), 1e-12);
  const Vec3 world_x = r.transpose() * Vec3::UnitX();  // in camera coordinates
  EXPECT_NEAR(world_x.dot(up), 0, 1e-12);               // horizontal
  EXPECT_GT(world_x.x(), 0.9);
  EXPECT_NEAR(r.determinant(), 1, 1e-12);
}

}  // namespace
}  // namespace doasido::recon
