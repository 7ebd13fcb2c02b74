// Object reconstruction metrics (REFERENCE.md §4): both surfaces are sampled
// area-weighted with a fixed seed (10k points, as iHOI and DiffHOI do), and
// nearest-neighbour distances are taken both ways, in metres.
//   F@tau     = 2PR / (P + R), P = mean(d_pred->gt < tau), R = mean(d_gt->pred < tau)
//   cd_sq_cm2 = mean(d_pred->gt^2) + mean(d_gt->pred^2), in cm^2 (iHOI, DiffHOI, gSDF)
//   cd_l1_cm  = (mean(d_pred->gt) + mean(d_gt->pred)) / 2, in cm (Any6D)
// Chamfer distance is defined differently across papers, so both are
// reported under these labels. Alignment (hand-root frame, ICP, Sim(3)) is
// the caller's job: these functions compare surfaces as given.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/config.h"
#include "core/mesh.h"

namespace doasido::recon {

using Points3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

struct ReconMetricsConfig {
  int samples = 10000;       // points per surface
  std::uint64_t seed = 0;    // sampling seed (pred and gt use seed and seed + 1)
  double tau_5mm = 0.005;    // metres
  double tau_10mm = 0.010;   // metres
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ReconMetricsConfig, samples, seed, tau_5mm,
                                                tau_10mm)

struct ReconMetrics {
  double precision_5mm = 0, recall_5mm = 0, f_5mm = 0;
  double precision_10mm = 0, recall_10mm = 0, f_10mm = 0;
  double cd_sq_cm2 = 0;
  double cd_l1_cm = 0;
  double mean_pred_to_gt_m = 0;  // mean nearest-neighbour distance, metres
  double mean_gt_to_pred_m = 0;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ReconMetrics, precision_5mm, recall_5mm, f_5mm,
                                                precision_10mm, recall_10mm, f_10mm, cd_sq_cm2,
                                                cd_l1_cm, mean_pred_to_gt_m, mean_gt_to_pred_m)

// `count` points uniformly distributed over the mesh surface: a triangle is
// picked with probability proportional to its area, then a point uniformly
// inside it. Deterministic for a given seed on every platform (own
// 53-bit uniform draw from std::mt19937_64). Throws Error("bad_mesh") for a
// mesh without area.
Points3 SampleSurface(const TriMesh& mesh, int count, std::uint64_t seed);

// Exact nearest-neighbour queries over a fixed point set (a k-d tree).
class NearestNeighbours {
 public:
  explicit NearestNeighbours(const Points3& points);
  // Distance from `q` to the closest point of the set (+inf for an empty set).
  double Distance(const Eigen::Vector3d& q) const;
  // Distance from every row of `queries`.
  std::vector<double> Distances(const Points3& queries) const;
  // Row index of the point closest to `q` (-1 for an empty set).
  Eigen::Index Nearest(const Eigen::Vector3d& q) const;

 private:
  struct Node {
    int point;        // index into points_
    int axis;         // split axis, -1 for a leaf
    int left, right;  // child node indices, -1 when absent
  };
  int Build(std::vector<int>& idx, int begin, int end);
  void Search(int node, const Eigen::Vector3d& q, double& best_sq, int& best) const;

  Points3 points_;
  std::vector<Node> nodes_;
  int root_ = -1;
};

// 2PR / (P + R), 0 when both are 0.
double FScore(double precision, double recall);

// Metrics between two point sets already sampled from the surfaces.
ReconMetrics ComparePoints(const Points3& pred, const Points3& gt,
                           const ReconMetricsConfig& config = {});

// Samples both meshes (config.samples points; pred with config.seed, gt with
// config.seed + 1) and compares them.
ReconMetrics CompareSurfaces(const TriMesh& pred, const TriMesh& gt,
                             const ReconMetricsConfig& config = {});

}  // namespace doasido::recon
