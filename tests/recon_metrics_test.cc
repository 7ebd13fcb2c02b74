// Reconstruction metrics against answers known in closed form: concentric
// spheres (every nearest distance equals the gap), hand-computed Chamfer and
// F-score on tiny sets, area-proportional sampling, and the k-d tree against
// brute force.
#include "recon/recon_metrics.h"

#include <cmath>
#include <map>
#include <random>

#include <gtest/gtest.h>

namespace doasido::recon {
namespace {

// An icosphere of radius r: the icosahedron subdivided `levels` times with
// vertices pushed onto the sphere.
TriMesh Icosphere(double r, int levels) {
  const double p = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> v = {{-1, p, 0}, {1, p, 0},  {-1, -p, 0}, {1, -p, 0},
                                    {0, -1, p}, {0, 1, p},  {0, -1, -p}, {0, 1, -p},
                                    {p, 0, -1}, {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[static_cast<size_t>(a)] + v[static_cast<size_t>(b)]) / 2);
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const auto& t : f) {
      const int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      next.insert(next.end(), {{t[0], a, c}, {t[1], b, a}, {t[2], c, b}, {a, b, c}});
    }
    f = next;
  }
  TriMesh m;
  m.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) {
    m.vertices.row(static_cast<Eigen::Index>(i)) = v[i].normalized().transpose() * r;
  }
  m.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t i = 0; i < f.size(); ++i) m.faces.row(static_cast<Eigen::Index>(i)) = f[i];
  return m;
}

TEST(ReconMetricsTest, ConcentricSpherePointsAreExactlyTheGapApart) {
  // Points on a sphere of radius r and the same directions at radius r + d:
  // the nearest point to each is its own radial partner, at distance d.
  const double r = 0.05;
  const Points3 dirs = SampleSurface(Icosphere(1.0, 3), 5000, 11);
  Points3 gt(dirs.rows(), 3), pred(dirs.rows(), 3);
  for (Eigen::Index i = 0; i < dirs.rows(); ++i) gt.row(i) = dirs.row(i).normalized() * r;
  for (double d : {0.003, 0.007, 0.012}) {
    for (Eigen::Index i = 0; i < dirs.rows(); ++i) pred.row(i) = dirs.row(i).normalized() * (r + d);
    const ReconMetrics m = ComparePoints(pred, gt);
    EXPECT_NEAR(m.mean_pred_to_gt_m, d, 1e-12);
    EXPECT_NEAR(m.mean_gt_to_pred_m, d, 1e-12);
    EXPECT_NEAR(m.cd_sq_cm2, 2 * (d * 100) * (d * 100), 1e-9);
    EXPECT_NEAR(m.cd_l1_cm, d * 100, 1e-9);
    EXPECT_EQ(m.f_5mm, d < 0.005 ? 1.0 : 0.0);
    EXPECT_EQ(m.f_10mm, d < 0.010 ? 1.0 : 0.0);
  }
}

TEST(ReconMetricsTest, ConcentricSphereMeshesBracketTheGap) {
  // Sampled independently, distances are the gap d plus at most the
  // sampling spacing; with d = 8 mm every distance is above 5 mm and below
  // 10 mm, so F@5mm = 0 and F@10mm = 1 exactly.
  const double r = 0.05, d = 0.008;
  const ReconMetrics m = CompareSurfaces(Icosphere(r + d, 4), Icosphere(r, 4));
  EXPECT_EQ(m.f_5mm, 0.0);
  EXPECT_EQ(m.f_10mm, 1.0);
  EXPECT_GT(m.mean_pred_to_gt_m, d - 1e-4);
  EXPECT_LT(m.mean_pred_to_gt_m, d + 1e-3);
  EXPECT_GT(m.cd_l1_cm, (d - 1e-4) * 100);
  EXPECT_LT(m.cd_l1_cm, (d + 1e-3) * 100);
  // The same surface sampled twice matches itself at 5 mm.
  const ReconMetrics same = CompareSurfaces(Icosphere(r, 4), Icosphere(r, 4));
  EXPECT_EQ(same.f_5mm, 1.0);
  EXPECT_LT(same.cd_l1_cm, 0.1);
}

TEST(ReconMetricsTest, HandComputedChamferAndFScore) {
  Points3 pred(1, 3), gt(2, 3);
  pred << 0, 0, 0;
  gt << 0.004, 0, 0, 0.03, 0, 0;
  const ReconMetrics m = ComparePoints(pred, gt);
  // pred->gt: 0.4 cm. gt->pred: 0.4 cm, 3 cm.
  EXPECT_EQ(m.precision_5mm, 1.0);
  EXPECT_EQ(m.recall_5mm, 0.5);
  EXPECT_NEAR(m.f_5mm, 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(m.cd_sq_cm2, 0.16 + (0.16 + 9.0) / 2, 1e-12);
  EXPECT_NEAR(m.cd_l1_cm, 0.5 * (0.4 + (0.4 + 3.0) / 2), 1e-12);
  EXPECT_EQ(FScore(0, 0), 0.0);
}

TEST(ReconMetricsTest, SamplingIsAreaWeightedOnTheSurfaceAndSeeded) {
  // Two triangles in the z = 0 plane with areas 1/2 and 3/2.
  TriMesh m;
  m.vertices.resize(6, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0, 5, 0, 0, 2, 1, 0;
  m.faces.resize(2, 3);
  m.faces << 0, 1, 2, 3, 4, 5;
  const int n = 20000;
  const Points3 p = SampleSurface(m, n, 5);
  int in_small = 0;
  Eigen::Vector3d mean_small = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(p(i, 2), 0.0);
    if (p(i, 0) <= 1.0) {
      ++in_small;
      mean_small += p.row(i).transpose();
      EXPECT_LE(p(i, 0) + p(i, 1), 1.0 + 1e-12);  // inside the small triangle
    }
  }
  // Expected fraction 1/4; binomial standard deviation ~0.003.
  EXPECT_NEAR(static_cast<double>(in_small) / n, 0.25, 0.015);
  // Uniform inside a triangle: the sample mean is its centroid (1/3, 1/3).
  mean_small /= in_small;
  EXPECT_NEAR(mean_small.x(), 1.0 / 3, 0.01);
  EXPECT_NEAR(mean_small.y(), 1.0 / 3, 0.01);
  EXPECT_EQ(SampleSurface(m, 100, 5), SampleSurface(m, 100, 5));
  EXPECT_NE(SampleSurface(m, 100, 5), SampleSurface(m, 100, 6));
}

TEST(ReconMetricsTest, KdTreeMatchesBruteForce) {
  std::mt19937 rng(9);
  std::normal_distribution<double> nd;
  Points3 set(3000, 3), queries(500, 3);
  for (Eigen::Index i = 0; i < set.size(); ++i) set.data()[i] = nd(rng);
  for (Eigen::Index i = 0; i < queries.size(); ++i) queries.data()[i] = 1.5 * nd(rng);
  set.row(7) = set.row(8);  // duplicates are fine
  const std::vector<double> fast = NearestNeighbours(set).Distances(queries);
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    const double brute = (set.rowwise() - queries.row(q)).rowwise().norm().minCoeff();
    EXPECT_DOUBLE_EQ(fast[static_cast<size_t>(q)], brute) << "query " << q;
  }
}

TEST(ReconMetricsTest, DegenerateInputIsRejected) {
  TriMesh flat;
  flat.vertices.resize(3, 3);
  flat.vertices << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  flat.faces.resize(1, 3);
  flat.faces << 0, 1, 2;
  EXPECT_THROW(SampleSurface(flat, 10, 0), Error);
  EXPECT_THROW(ComparePoints(Points3(0, 3), Points3::Zero(1, 3)), Error);
}

}  // namespace
}  // namespace doasido::recon
