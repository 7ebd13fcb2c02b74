#include "recon/recon_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "core/error.h"

namespace doasido::recon {
namespace {

// Uniform double in [0, 1) from the top 53 bits: unlike
// std::uniform_real_distribution, identical across standard libraries.
double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

}  // namespace

Points3 SampleSurface(const TriMesh& mesh, int count, std::uint64_t seed) {
  const int nf = mesh.num_faces();
  std::vector<double> cumulative(static_cast<size_t>(nf));
  double total = 0;
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2));
    total += 0.5 * (b - a).cross(c - a).norm();
    cumulative[static_cast<size_t>(f)] = total;
  }
  if (!(total > 0) || !std::isfinite(total)) {
    throw Error("bad_mesh", "surface has no area to sample", {.field = "faces"});
  }
  std::mt19937_64 rng(seed);
  Points3 out(count, 3);
  for (int i = 0; i < count; ++i) {
    const double pick = Uniform01(rng) * total;
    const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), pick);
    const int f = static_cast<int>(std::min<std::ptrdiff_t>(it - cumulative.begin(), nf - 1));
    // Square-root warping makes (1 - s, s(1 - r2), s r2) uniform over the triangle.
    const double s = std::sqrt(Uniform01(rng));
    const double r2 = Uniform01(rng);
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2));
    out.row(i) = ((1 - s) * a + s * (1 - r2) * b + s * r2 * c).transpose();
  }
  return out;
}

NearestNeighbours::NearestNeighbours(const Points3& points) : points_(points) {
  std::vector<int> idx(static_cast<size_t>(points.rows()));
  std::iota(idx.begin(), idx.end(), 0);
  nodes_.reserve(idx.size());
  root_ = Build(idx, 0, static_cast<int>(idx.size()));
}

int NearestNeighbours::Build(std::vector<int>& idx, int begin, int end) {
  if (begin >= end) return -1;
  // Split on the axis of largest extent for well-shaped cells on thin surfaces.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (int i = begin; i < end; ++i) {
    lo = lo.cwiseMin(points_.row(idx[static_cast<size_t>(i)]).transpose());
    hi = hi.cwiseMax(points_.row(idx[static_cast<size_t>(i)]).transpose());
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const int mid = begin + (end - begin) / 2;
  std::nth_element(idx.begin() + begin, idx.begin() + mid, idx.begin() + end,
                   [&](int a, int b) { return points_(a, axis) < points_(b, axis); });
  const int node = static_cast<int>(nodes_.size());
  nodes_.push_back({idx[static_cast<size_t>(mid)], axis, -1, -1});
  const int left = Build(idx, begin, mid);
  const int right = Build(idx, mid + 1, end);
  nodes_[static_cast<size_t>(node)].left = left;
  nodes_[static_cast<size_t>(node)].right = right;
  return node;
}

void NearestNeighbours::Search(int node, const Eigen::Vector3d& q, double& best_sq,
                               int& best) const {
  while (node >= 0) {
    const Node& n = nodes_[static_cast<size_t>(node)];
    const double d_sq = (points_.row(n.point).transpose() - q).squaredNorm();
    if (d_sq < best_sq) {
      best_sq = d_sq;
      best = n.point;
    }
    const double diff = q(n.axis) - points_(n.point, n.axis);
    const int near = diff < 0 ? n.left : n.right;
    const int far = diff < 0 ? n.right : n.left;
    if (far >= 0 && diff * diff < best_sq) {
      Search(near, q, best_sq, best);
      if (diff * diff < best_sq) node = far;
      else node = -1;
    } else {
      node = near;
    }
  }
}

double NearestNeighbours::Distance(const Eigen::Vector3d& q) const {
  double best_sq = std::numeric_limits<double>::infinity();
  int best = -1;
  Search(root_, q, best_sq, best);
  return std::sqrt(best_sq);
}

Eigen::Index NearestNeighbours::Nearest(const Eigen::Vector3d& q) const {
  double best_sq = std::numeric_limits<double>::infinity();
  int best = -1;
  Search(root_, q, best_sq, best);
  return best;
}

std::vector<double> NearestNeighbours::Distances(const Points3& queries) const {
  std::vector<double> out(static_cast<size_t>(queries.rows()));
  for (Eigen::Index i = 0; i < queries.rows(); ++i) {
    out[static_cast<size_t>(i)] = Distance(queries.row(i).transpose());
  }
  return out;
}

double FScore(double precision, double recall) {
  return precision + recall > 0 ? 2 * precision * recall / (precision + recall) : 0.0;
}

ReconMetrics ComparePoints(const Points3& pred, const Points3& gt,
                           const ReconMetricsConfig& config) {
  if (pred.rows() == 0 || gt.rows() == 0) {
    throw Error("bad_array", "cannot compare an empty point set", {.field = "points"});
  }
  const std::vector<double> d_pg = NearestNeighbours(gt).Distances(pred);
  const std::vector<double> d_gp = NearestNeighbours(pred).Distances(gt);
  auto mean = [](const std::vector<double>& d, auto f) {
    double s = 0;
    for (double v : d) s += f(v);
    return s / static_cast<double>(d.size());
  };
  auto below = [&](const std::vector<double>& d, double tau) {
    return mean(d, [tau](double v) { return v < tau ? 1.0 : 0.0; });
  };
  ReconMetrics m;
  m.precision_5mm = below(d_pg, config.tau_5mm);
  m.recall_5mm = below(d_gp, config.tau_5mm);
  m.f_5mm = FScore(m.precision_5mm, m.recall_5mm);
  m.precision_10mm = below(d_pg, config.tau_10mm);
  m.recall_10mm = below(d_gp, config.tau_10mm);
  m.f_10mm = FScore(m.precision_10mm, m.recall_10mm);
  m.mean_pred_to_gt_m = mean(d_pg, [](double v) { return v; });
  m.mean_gt_to_pred_m = mean(d_gp, [](double v) { return v; });
  const double sq_pg = mean(d_pg, [](double v) { return v * v; });
  const double sq_gp = mean(d_gp, [](double v) { return v * v; });
  m.cd_sq_cm2 = (sq_pg + sq_gp) * 1e4;  // m^2 -> cm^2
  m.cd_l1_cm = 0.5 * (m.mean_pred_to_gt_m + m.mean_gt_to_pred_m) * 1e2;
  return m;
}

ReconMetrics CompareSurfaces(const TriMesh& pred, const TriMesh& gt,
                             const ReconMetricsConfig& config) {
  return ComparePoints(SampleSurface(pred, config.samples, config.seed),
                       SampleSurface(gt, config.samples, config.seed + 1), config);
}

}  // namespace doasido::recon
