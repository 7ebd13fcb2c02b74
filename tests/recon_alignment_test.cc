// Alignment modes recover transforms that were applied on purpose: Umeyama
// from exact correspondences, ICP from a small offset, multi-start Sim(3)
// from a large turn and a scale change, the hand-root frame from a motion
// shared by hand and object.
#include "eval/alignment.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace doasido::recon {
namespace {

constexpr double kPi = 3.14159265358979323846;

// An axis-aligned box [lo, hi] as 12 outward triangles.
TriMesh Box(const Vec3& lo, const Vec3& hi) {
  TriMesh m;
  m.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) {
    m.vertices.row(i) << (i & 1 ? hi.x() : lo.x()), (i & 2 ? hi.y() : lo.y()),
        (i & 4 ? hi.z() : lo.z());
  }
  m.faces.resize(12, 3);
  m.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2,
      4, 6, 1, 3, 5, 3, 7, 5;
  return m;
}

TriMesh Concat(const TriMesh& a, const TriMesh& b) {
  TriMesh m;
  m.vertices.resize(a.num_vertices() + b.num_vertices(), 3);
  m.vertices << a.vertices, b.vertices;
  m.faces.resize(a.num_faces() + b.num_faces(), 3);
  m.faces << a.faces, (b.faces.array() + a.num_vertices()).matrix();
  return m;
}

// An L-shaped object with no rotational symmetry (about 10 x 6 x 3 cm).
TriMesh LShape() {
  return Concat(Box(Vec3(0, 0, 0), Vec3(0.10, 0.02, 0.03)),
                Box(Vec3(0, 0.02, 0), Vec3(0.025, 0.06, 0.015)));
}

Similarity Known(double angle_deg, const Vec3& axis, const Vec3& t, double s) {
  Similarity x;
  x.R = Eigen::AngleAxisd(angle_deg * kPi / 180, axis.normalized()).toRotationMatrix();
  x.t = t;
  x.s = s;
  return x;
}

TEST(AlignmentTest, UmeyamaRecoversSimilarityFromCorrespondences) {
  std::mt19937 rng(4);
  std::normal_distribution<double> n;
  Points3 src(50, 3);
  for (Eigen::Index i = 0; i < src.size(); ++i) src.data()[i] = n(rng);
  const Similarity truth = Known(123, Vec3(1, -2, 0.5), Vec3(0.3, -0.1, 2.0), 1.7);
  const Points3 dst = truth.Apply(src);
  const Similarity sim = Umeyama(src, dst, true);
  EXPECT_LT((sim.R - truth.R).norm(), 1e-10);
  EXPECT_NEAR(sim.s, truth.s, 1e-10);
  EXPECT_LT((sim.t - truth.t).norm(), 1e-10);
  const Similarity rigid = Umeyama(src, truth.Apply(src) / truth.s, false);
  EXPECT_EQ(rigid.s, 1.0);
  EXPECT_LT((rigid.R - truth.R).norm(), 1e-10);
  // A mirror image cannot be matched by a rotation: the result stays proper.
  Points3 mirrored = src;
  mirrored.col(0) *= -1;
  EXPECT_NEAR(Umeyama(src, mirrored, false).R.determinant(), 1.0, 1e-12);
}

TEST(AlignmentTest, IcpRecoversSmallRigidOffset) {
  const Points3 gt = SampleSurface(LShape(), 4000, 1);
  const Similarity truth = Known(8, Vec3(0.3, 1, 0.2), Vec3(0.01, -0.005, 0.008), 1.0);
  const Points3 src = truth.Apply(gt);
  Similarity init;
  init.t = (gt.colwise().mean() - src.colwise().mean()).transpose();
  const IcpResult r = Icp(src, gt, init, false);
  EXPECT_LT(r.rms, 1e-6);
  // The recovered transform undoes the known one.
  const Mat3 r_total = r.transform.R * truth.R;
  EXPECT_LT(Eigen::AngleAxisd(r_total).angle(), 1e-5);
}

TEST(AlignmentTest, MultiStartSim3RecoversLargeTurnAndScale) {
  const Points3 gt = SampleSurface(LShape(), 3000, 2);
  const Similarity truth = Known(150, Vec3(1, 1, 0.3), Vec3(0.2, 0.1, 0.5), 0.7);
  const Points3 src = truth.Apply(gt);
  const IcpResult r = MultiStartSim3(src, gt);
  EXPECT_LT(r.rms, 1e-6);
  EXPECT_NEAR(r.transform.s * truth.s, 1.0, 1e-6);
}

TEST(AlignmentTest, ModesScoreAMovedPrediction) {
  const TriMesh gt = LShape();
  ReconMetricsConfig cfg;
  cfg.samples = 5000;  // ~1.7 mm spacing on this surface
  const Pose motion{Quat(Eigen::AngleAxisd(0.1, Vec3(0, 0, 1))), Vec3(0.012, 0.0, -0.006)};
  const TriMesh pred = gt.Transformed(motion);
  const ReconMetrics none = CompareAligned(pred, gt, AlignMode::kNone, cfg);
  const ReconMetrics icp = CompareAligned(pred, gt, AlignMode::kIcp, cfg);
  const ReconMetrics sim3 = CompareAligned(pred, gt, AlignMode::kSim3, cfg);
  EXPECT_LT(none.f_5mm, 0.6);
  EXPECT_GT(icp.f_5mm, 0.98);
  EXPECT_GT(sim3.f_5mm, 0.98);
  // Hand and object moved together: in the wrist frame nothing moved.
  const Pose gt_root{Quat(Eigen::AngleAxisd(0.4, Vec3(1, 0, 0))), Vec3(0.05, 0.02, 0.4)};
  const ReconMetrics root =
      CompareAligned(pred, gt, AlignMode::kHandRoot, cfg, motion * gt_root, gt_root);
  const ReconMetrics same = CompareAligned(gt, gt, AlignMode::kNone, cfg);
  EXPECT_NEAR(root.f_5mm, same.f_5mm, 1e-12);
  EXPECT_NEAR(root.cd_l1_cm, same.cd_l1_cm, 1e-9);
}

TEST(AlignmentTest, SummaryGivesMeanAndMedian) {
  std::vector<ReconMetrics> frames(4);
  const double f[4] = {0.2, 0.9, 0.4, 0.5};
  for (int i = 0; i < 4; ++i) frames[static_cast<size_t>(i)].f_5mm = f[i];
  const Json s = SummariseMetrics(frames);
  EXPECT_EQ(s["frames"], 4);
  EXPECT_NEAR(s["f_5mm"]["mean"].get<double>(), 0.5, 1e-15);
  EXPECT_NEAR(s["f_5mm"]["median"].get<double>(), 0.45, 1e-15);
  EXPECT_TRUE(s.contains("cd_sq_cm2"));
}

TEST(AlignmentTest, ModeNamesParse) {
  for (AlignMode m : {AlignMode::kNone, AlignMode::kHandRoot, AlignMode::kIcp, AlignMode::kSim3}) {
    EXPECT_EQ(ParseAlignMode(AlignModeName(m)), m);
  }
  EXPECT_THROW(ParseAlignMode("procrustes"), Error);
}

}  // namespace
}  // namespace doasido::recon
