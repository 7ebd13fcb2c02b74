#include "eval/alignment.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/SVD>

#include "core/error.h"

namespace doasido::recon {
namespace {

Eigen::RowVector3d Centroid(const Points3& p) { return p.colwise().mean(); }

double RmsRadius(const Points3& p) {
  return std::sqrt((p.rowwise() - Centroid(p)).rowwise().squaredNorm().mean());
}

// The 24 rotations that map coordinate axes onto signed coordinate axes.
std::vector<Mat3> AxisRotations() {
  std::vector<Mat3> out;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& perm : perms) {
    for (int signs = 0; signs < 8; ++signs) {
      Mat3 r = Mat3::Zero();
      for (int row = 0; row < 3; ++row) r(row, perm[row]) = (signs >> row) & 1 ? -1.0 : 1.0;
      if (r.determinant() > 0) out.push_back(r);
    }
  }
  return out;
}

}  // namespace

Points3 Similarity::Apply(const Points3& points) const {
  Points3 out = (s * (points * R.transpose())).eval();
  out.rowwise() += t.transpose();
  return out;
}

Similarity Umeyama(const Points3& src, const Points3& dst, bool with_scale) {
  if (src.rows() != dst.rows() || src.rows() < 3) {
    throw Error("bad_array", "Umeyama needs two equally long sets of at least 3 points",
                {.field = "points"});
  }
  const Eigen::RowVector3d mu_s = Centroid(src), mu_d = Centroid(dst);
  const Points3 xs = src.rowwise() - mu_s;
  const Points3 xd = dst.rowwise() - mu_d;
  const double n = static_cast<double>(src.rows());
  const Mat3 cov = xd.transpose() * xs / n;  // sum of dst_i src_i^T
  Eigen::JacobiSVD<Mat3> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 d = Mat3::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) d(2, 2) = -1;
  Similarity out;
  out.R = svd.matrixU() * d * svd.matrixV().transpose();
  if (with_scale) {
    const double var_s = xs.rowwise().squaredNorm().sum() / n;
    if (!(var_s > 0)) throw Error("bad_array", "source points coincide", {.field = "points"});
    out.s = (svd.singularValues().asDiagonal() * d).trace() / var_s;
  }
  out.t = mu_d.transpose() - out.s * out.R * mu_s.transpose();
  return out;
}

IcpResult Icp(const Points3& src, const Points3& dst, const Similarity& init, bool with_scale,
              const IcpConfig& config) {
  const NearestNeighbours dst_tree(dst);
  IcpResult best;
  best.transform = init;
  best.rms = std::numeric_limits<double>::infinity();
  Similarity current = init;
  // Pairs both ways: src -> nearest dst and dst -> nearest moved src. The
  // second set keeps a free scale from shrinking src into dst's interior.
  Points3 from(src.rows() + dst.rows(), 3), to(src.rows() + dst.rows(), 3);
  for (int it = 0; it < config.max_iterations; ++it) {
    const Points3 moved = current.Apply(src);
    const NearestNeighbours src_tree(moved);
    double sum_sq = 0;
    for (Eigen::Index i = 0; i < src.rows(); ++i) {
      const Eigen::Index j = dst_tree.Nearest(moved.row(i).transpose());
      from.row(i) = src.row(i);
      to.row(i) = dst.row(j);
      sum_sq += (moved.row(i) - dst.row(j)).squaredNorm();
    }
    for (Eigen::Index j = 0; j < dst.rows(); ++j) {
      const Eigen::Index i = src_tree.Nearest(dst.row(j).transpose());
      from.row(src.rows() + j) = src.row(i);
      to.row(src.rows() + j) = dst.row(j);
      sum_sq += (moved.row(i) - dst.row(j)).squaredNorm();
    }
    const double rms = std::sqrt(sum_sq / static_cast<double>(from.rows()));
    if (!(rms < best.rms)) break;
    const bool converged = best.rms - rms < config.tolerance;
    best = {current, rms, it + 1};
    if (converged) break;
    current = Umeyama(from, to, with_scale);
  }
  return best;
}

IcpResult MultiStartSim3(const Points3& src, const Points3& dst, const IcpConfig& config) {
  // Starts run on at most ~1500 points of each set; the winner is refined on all.
  auto subsample = [](const Points3& p) {
    const Eigen::Index step = std::max<Eigen::Index>(1, p.rows() / 1500);
    Points3 out((p.rows() + step - 1) / step, 3);
    for (Eigen::Index i = 0; i < out.rows(); ++i) out.row(i) = p.row(i * step);
    return out;
  };
  const Points3 src_small = subsample(src), dst_small = subsample(dst);
  const Vec3 mu_s = Centroid(src).transpose(), mu_d = Centroid(dst).transpose();
  const double scale = RmsRadius(dst) / std::max(RmsRadius(src), 1e-12);
  // Starts only need ranking, so they stop early.
  IcpConfig start_config = config;
  start_config.max_iterations = std::min(config.max_iterations, 20);
  IcpResult best;
  best.rms = std::numeric_limits<double>::infinity();
  for (const Mat3& r : AxisRotations()) {
    Similarity init;
    init.R = r;
    init.s = scale;
    init.t = mu_d - scale * r * mu_s;
    const IcpResult res = Icp(src_small, dst_small, init, true, start_config);
    if (res.rms < best.rms) best = res;
  }
  return Icp(src, dst, best.transform, true, config);
}

std::string AlignModeName(AlignMode mode) {
  switch (mode) {
    case AlignMode::kNone: return "none";
    case AlignMode::kHandRoot: return "hand_root";
    case AlignMode::kIcp: return "icp";
    case AlignMode::kSim3: return "sim3";
  }
  return "none";
}

AlignMode ParseAlignMode(const std::string& name) {
  for (AlignMode m : {AlignMode::kNone, AlignMode::kHandRoot, AlignMode::kIcp, AlignMode::kSim3}) {
    if (AlignModeName(m) == name) return m;
  }
  throw Error("bad_config", "unknown alignment mode '" + name + "' (none, hand_root, icp, sim3)",
              {.field = "align"});
}

ReconMetrics CompareAligned(const TriMesh& pred, const TriMesh& gt, AlignMode mode,
                            const ReconMetricsConfig& config, const Pose& pred_root,
                            const Pose& gt_root) {
  Points3 p = SampleSurface(pred, config.samples, config.seed);
  Points3 g = SampleSurface(gt, config.samples, config.seed + 1);
  switch (mode) {
    case AlignMode::kNone: break;
    case AlignMode::kHandRoot: {
      const Pose pi = pred_root.Inverse(), gi = gt_root.Inverse();
      auto to_root = [](const Pose& inverse, Points3& points) {
        for (Eigen::Index i = 0; i < points.rows(); ++i) {
          points.row(i) = (inverse * Vec3(points.row(i).transpose())).transpose();
        }
      };
      to_root(pi, p);
      to_root(gi, g);
      break;
    }
    case AlignMode::kIcp: {
      Similarity init;  // start from the centroid offset
      init.t = (Centroid(g) - Centroid(p)).transpose();
      p = Icp(p, g, init, false).transform.Apply(p);
      break;
    }
    case AlignMode::kSim3: p = MultiStartSim3(p, g).transform.Apply(p); break;
  }
  return ComparePoints(p, g, config);
}

Json SummariseMetrics(const std::vector<ReconMetrics>& per_frame) {
  Json out = Json::object();
  out["frames"] = per_frame.size();
  if (per_frame.empty()) return out;
  Json fields = Json::array();
  for (const ReconMetrics& m : per_frame) fields.push_back(Json(m));
  for (const auto& [key, value] : fields[0].items()) {
    (void)value;
    std::vector<double> v;
    for (const Json& f : fields) v.push_back(f[key].get<double>());
    double mean = 0;
    for (double x : v) mean += x;
    mean /= static_cast<double>(v.size());
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    const double median = n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    out[key] = {{"mean", mean}, {"median", median}};
  }
  return out;
}

}  // namespace doasido::recon
