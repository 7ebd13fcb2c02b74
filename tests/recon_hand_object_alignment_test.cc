// Seed appendix "Hand-Object Alignment": the visible-hand centroid equals a
// brute-force ray cast; on noise-free data rendered by ray casting and seen
// through a point map with a known per-frame scale error, the alignment
// recovers exactly that scale; frames without evidence are skipped and
// short gaps interpolated.
#include "recon/align/hand_object_alignment.h"

#include <cmath>
#include <limits>
#include <optional>

#include <gtest/gtest.h>

#include "recon/ray_caster.h"
#include "recon/align/visible_centroid.h"

namespace doasido::recon {
namespace {

constexpr int kW = 120, kH = 90;

Mat3 TestK() {
  Mat3 k;
  k << 110, 0, 60, 0, 110, 45, 0, 0, 1;
  return k;
}

TriMesh Box(const Vec3& half) {
  TriMesh m;
  m.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) {
    m.vertices.row(i) << ((i & 1) ? half.x() : -half.x()), ((i >> 1 & 1) ? half.y() : -half.y()),
        ((i >> 2 & 1) ? half.z() : -half.z());
  }
  m.faces.resize(12, 3);
  m.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4,
      6, 1, 3, 5, 3, 7, 5;
  return m;
}

// Möller-Trumbore over every triangle: the reference the Embree caster must match.
std::optional<double> BruteForceHit(const TriMesh& m, const Vec3& dir) {
  std::optional<double> best;
  for (int f = 0; f < m.num_faces(); ++f) {
    const Vec3 a = m.vertices.row(m.faces(f, 0)), b = m.vertices.row(m.faces(f, 1)),
               c = m.vertices.row(m.faces(f, 2));
    const Vec3 e1 = b - a, e2 = c - a, p = dir.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-15) continue;
    const Vec3 s = -a;
    const double u = s.dot(p) / det;
    const Vec3 q = s.cross(e1);
    const double v = dir.dot(q) / det, t = e2.dot(q) / det;
    if (u < 0 || v < 0 || u + v > 1 || t <= 0) continue;
    if (!best || t < *best) best = t;
  }
  return best;
}

TEST(VisibleCentroid, EqualsBruteForceRayCast) {
  const Pose pose{Quat(Eigen::AngleAxisd(0.7, Vec3(0.3, 1, 0.2).normalized())), Vec3(0.013, -0.021, 0.43)};
  const TriMesh hand = Box(Vec3(0.041, 0.033, 0.027)).Transformed(pose);
  cv::Mat mask = cv::Mat::zeros(kH, kW, CV_8U);
  cv::Mat points(kH, kW, CV_32FC3, cv::Scalar(0.1, 0.2, 1.0));
  for (int v = 10; v < 80; ++v)
    for (int u = 15; u < 100; ++u) mask.at<std::uint8_t>(v, u) = 255;
  const RayCaster caster(hand.vertices, hand.faces);
  const VisibleHand got = CastHandMask(caster, TestK(), mask, points);

  const Mat3 k_inv = TestK().inverse();
  Vec3 sum = Vec3::Zero();
  int hits = 0;
  for (int v = 0; v < kH; ++v) {
    for (int u = 0; u < kW; ++u) {
      if (!mask.at<std::uint8_t>(v, u)) continue;
      const Vec3 dir = (k_inv * Vec3(u, v, 1)).normalized();
      if (const auto t = BruteForceHit(hand, dir)) {
        sum += *t * dir;
        ++hits;
      }
    }
  }
  ASSERT_GT(hits, 200);
  EXPECT_EQ(got.hits, hits);
  EXPECT_EQ(got.rays, cv::countNonZero(mask));
  EXPECT_LT((got.MeshCentroid() - sum / hits).norm(), 2e-6);
  EXPECT_LT((got.MapCentroid() - Vec3(0.1, 0.2, 1.0)).norm(), 1e-6);
}

// A square facing the camera: its visible points' centroid is its centre
// both on the mesh and over its pixels, so the alignment must be exact.
TriMesh Square(double half) {
  TriMesh m;
  m.vertices.resize(4, 3);
  m.vertices << -half, -half, 0, half, -half, 0, half, half, 0, -half, half, 0;
  m.faces.resize(2, 3);
  m.faces << 0, 1, 2, 0, 2, 3;
  return m;
}

struct Scene {
  ClipBundle bundle;
  std::vector<Pose> model_poses;  // object->camera in point-map units
  std::vector<Vec3> true_t;
};

// Frames rendered by ray casting: hand box and object square in metres;
// the point map is the metric scene times sigma[t] (MoGe's per-frame scale
// error), the object translation likewise.
Scene Render(const std::vector<double>& sigma) {
  Scene s;
  ClipBundle& b = s.bundle;
  b.width = kW;
  b.height = kH;
  b.frames = static_cast<int>(sigma.size());
  b.fps = 30;
  b.K = {TestK()};
  const TriMesh hand_local = Box(Vec3(0.03, 0.02, 0.02));
  b.object_mesh = Square(0.5 * 9 / 110.0 * 0.5);  // 9 px wide at 0.5 m: edges on half pixels
  HandTrack hand;
  const Mat3 k_inv = TestK().inverse();
  for (int t = 0; t < b.frames; ++t) {
    const Pose hand_pose{Quat(Eigen::AngleAxisd(0.3 + 0.05 * t, Vec3::UnitY())),
                         Vec3(-0.06 + 0.004 * t, 0.01, 0.47)};
    const TriMesh hand_mesh = hand_local.Transformed(hand_pose);
    // The square's centre projects onto pixel (70 + t, 45).
    const Vec3 centre = 0.5 * (k_inv * Vec3(70 + t, 45, 1));
    const Pose object_pose{Quat::Identity(), centre};
    s.true_t.push_back(centre);
    s.model_poses.push_back({object_pose.q, sigma[t] * centre});
    const TriMesh object_mesh = b.object_mesh->Transformed(object_pose);
    const RayCaster hc(hand_mesh.vertices, hand_mesh.faces), oc(object_mesh.vertices, object_mesh.faces);
    cv::Mat depth(kH, kW, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
    cv::Mat mh = cv::Mat::zeros(kH, kW, CV_8U), mo = mh.clone();
    for (int v = 0; v < kH; ++v) {
      for (int u = 0; u < kW; ++u) {
        const Vec3 dir = (k_inv * Vec3(u, v, 1)).normalized();
        const auto h = hc.FirstHit(Vec3::Zero(), dir), o = oc.FirstHit(Vec3::Zero(), dir);
        const double dh = h ? *h : 1e9, d_o = o ? *o : 1e9;
        if (std::min(dh, d_o) > 1e8) continue;
        const bool is_hand = dh < d_o;
        (is_hand ? mh : mo).at<std::uint8_t>(v, u) = 255;
        depth.at<float>(v, u) = static_cast<float>(sigma[t] * std::min(dh, d_o) * dir.z());
      }
    }
    b.depth.push_back(depth);
    b.mask_hand_right.push_back(mh);
    b.mask_object.push_back(mo);
    b.mask_hand_left.push_back(cv::Mat::zeros(kH, kW, CV_8U));
    hand.valid.push_back(true);
    hand.joints.push_back(Joints21::Constant(0.3));
    hand.verts.push_back(hand_mesh.vertices);
    hand.faces = hand_mesh.faces;
  }
  b.hand_right = hand;
  b.object_poses = s.model_poses;
  return s;
}

TEST(HandObjectAlignment, TranslationScaleIsTheLeastSquaresSolution) {
  const Vec3 t(0.1, -0.2, 0.9), c(0.01, 0.02, -0.03);
  const double s = TranslationScale(t, c, c + 0.8 * t + t.unitOrthogonal() * 0.05);
  EXPECT_NEAR(s, 0.8, 1e-12);
}

TEST(HandObjectAlignment, RecoversAKnownScaleExactlyOnNoiseFreeData) {
  const std::vector<double> sigma = {1.3, 0.8, 1.1, 0.95};
  const Scene s = Render(sigma);
  HandObjectAlignmentConfig config;
  const std::vector<bool> valid(sigma.size(), true);
  const HandObjectAlignment a = AlignHandObject(s.bundle, s.model_poses, valid, config);
  ASSERT_EQ(a.aligned_frames, 4);
  for (size_t t = 0; t < sigma.size(); ++t) {
    const FrameAlignment& f = a.frames[t];
    EXPECT_NEAR(f.k, 1 / sigma[t], 1e-5) << t;
    EXPECT_NEAR(a.scale[t], 1 / sigma[t], 1e-5) << t;
    EXPECT_LT((a.poses[t].t - s.true_t[t]).norm(), 1e-5) << t;
    EXPECT_EQ(a.fill[t], kFillAligned);
  }
}

TEST(HandObjectAlignment, SkipsFramesWithoutEvidenceAndInterpolatesShortGaps) {
  const std::vector<double> sigma = {1.2, 1.0, 0.9, 1.1, 1.0};
  Scene s = Render(sigma);
  s.bundle.mask_hand_right[2].setTo(0);            // no hand evidence
  s.bundle.mask_object[3].setTo(0);                // no object mask
  std::vector<bool> valid(sigma.size(), true);
  HandObjectAlignmentConfig config;
  config.max_gap_frames = 2;
  const HandObjectAlignment a = AlignHandObject(s.bundle, s.model_poses, valid, config);
  EXPECT_EQ(a.frames[2].skipped, kSkipNoHand);
  EXPECT_EQ(a.frames[3].skipped, kSkipNoObjectMask);
  EXPECT_EQ(a.fill[2], kFillInterpolated);
  EXPECT_EQ(a.fill[3], kFillInterpolated);
  EXPECT_NEAR(a.scale[2], (2.0 / 3) * (1 / 1.0) + (1.0 / 3) * (1 / 1.0), 1e-5);
  config.max_gap_frames = 1;  // the gap of two is now too long
  const HandObjectAlignment b = AlignHandObject(s.bundle, s.model_poses, valid, config);
  EXPECT_EQ(b.fill[2], kFillNone);
  EXPECT_TRUE(std::isnan(b.scale[2]));
}

TEST(HandObjectAlignment, SmoothingKeepsExactScalesOnNoiseFreeData) {
  const std::vector<double> sigma = {1.0, 1.0, 1.0, 1.0};
  const Scene s = Render(sigma);
  HandObjectAlignmentConfig config;
  config.smooth = true;
  const HandObjectAlignment a = AlignHandObject(s.bundle, s.model_poses, std::vector<bool>(4, true), config);
  // The object moves at constant velocity, so the acceleration prior is zero at the truth.
  for (int t = 0; t < 4; ++t) EXPECT_NEAR(a.scale[t], 1.0, 1e-4) << t;
}

TEST(HandObjectAlignment, ConfigRangesAreChecked) {
  HandObjectAlignmentConfig c;
  c.robust_scale = 0;
  EXPECT_THROW(CheckConfig(c, "recon.alignment"), Error);
}

}  // namespace
}  // namespace doasido::recon
