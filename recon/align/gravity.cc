#include "recon/align/gravity.h"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/SVD>

#include "core/config_check.h"
#include "recon/align/visible_centroid.h"

namespace doasido::recon {
namespace {

std::vector<Vec3> SamplePoints(const cv::Mat& points, const cv::Mat& exclude, int stride) {
  std::vector<Vec3> out;
  for (int v = 0; v < points.rows; v += stride) {
    const cv::Vec3f* p = points.ptr<cv::Vec3f>(v);
    for (int u = 0; u < points.cols; u += stride) {
      if (!exclude.empty() && exclude.at<std::uint8_t>(v, u)) continue;
      if (ValidPoint(p[u])) out.emplace_back(p[u][0], p[u][1], p[u][2]);
    }
  }
  return out;
}

// Least-squares plane through `pts` (smallest singular vector of the centred set).
SupportPlane RefinePlane(const std::vector<Vec3>& pts) {
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : pts) c += p;
  c /= static_cast<double>(pts.size());
  Mat3 cov = Mat3::Zero();
  for (const Vec3& p : pts) cov += (p - c) * (p - c).transpose();
  Eigen::JacobiSVD<Mat3> svd(cov, Eigen::ComputeFullU);
  SupportPlane plane;
  plane.normal = svd.matrixU().col(2);
  plane.offset = -plane.normal.dot(c);
  return plane;
}

// The largest plane among `pts` by RANSAC, refined on its inliers; the
// inliers are moved to `inliers`.
std::optional<SupportPlane> LargestPlane(const std::vector<Vec3>& pts, const GravityConfig& config,
                                         std::mt19937_64& rng, std::vector<bool>& inlier) {
  if (pts.size() < 3) return std::nullopt;
  std::uniform_int_distribution<size_t> pick(0, pts.size() - 1);
  size_t best = 0;
  Vec3 best_n = Vec3::Zero();
  double best_d = 0;
  for (int it = 0; it < config.ransac_iterations; ++it) {
    const Vec3 &a = pts[pick(rng)], &b = pts[pick(rng)], &c = pts[pick(rng)];
    Vec3 n = (b - a).cross(c - a);
    if (n.norm() < 1e-12) continue;
    n.normalize();
    const double d = -n.dot(a);
    size_t count = 0;
    for (const Vec3& p : pts) count += std::abs(n.dot(p) + d) < config.inlier_distance;
    if (count > best) {
      best = count;
      best_n = n;
      best_d = d;
    }
  }
  if (best < 3) return std::nullopt;
  std::vector<Vec3> in;
  inlier.assign(pts.size(), false);
  for (size_t i = 0; i < pts.size(); ++i) {
    if (std::abs(best_n.dot(pts[i]) + best_d) < config.inlier_distance) {
      inlier[i] = true;
      in.push_back(pts[i]);
    }
  }
  SupportPlane plane = RefinePlane(in);
  plane.inlier_share = static_cast<double>(in.size());  // a count until the caller divides
  return plane;
}

}  // namespace

void CheckConfig(const GravityConfig& c, const std::string& section) {
  RequireInRange(section, "ransac_iterations", c.ransac_iterations, 1, 1e7);
  RequireInRange(section, "inlier_distance", c.inlier_distance, 1e-6, 10);
  RequireInRange(section, "max_planes", c.max_planes, 1, 20);
  RequireInRange(section, "stride", c.stride, 1, 64);
  RequireInRange(section, "min_inlier_share", c.min_inlier_share, 0, 1);
}

std::optional<SupportPlane> FitSupportPlane(const cv::Mat& points, const cv::Mat& exclude,
                                            const Vec3& above, const GravityConfig& config) {
  std::vector<Vec3> pts = SamplePoints(points, exclude, config.stride);
  const double total = static_cast<double>(pts.size());
  std::mt19937_64 rng(config.seed);
  std::optional<SupportPlane> chosen;
  for (int k = 0; k < config.max_planes; ++k) {
    std::vector<bool> inlier;
    auto plane = LargestPlane(pts, config, rng, inlier);
    if (!plane) break;
    plane->inlier_share /= total;
    if (plane->inlier_share < config.min_inlier_share) break;
    if (plane->normal.dot(above) + plane->offset < 0) {
      plane->normal = -plane->normal;
      plane->offset = -plane->offset;
    }
    // The plane must lie below `above` by more than the inlier band, and
    // planes come out largest first: the first that qualifies is chosen.
    if (plane->normal.dot(above) + plane->offset > config.inlier_distance) {
      chosen = plane;
      break;
    }
    std::vector<Vec3> rest;
    for (size_t i = 0; i < pts.size(); ++i) {
      if (!inlier[i]) rest.push_back(pts[i]);
    }
    pts.swap(rest);
  }
  return chosen;
}

GravityEstimate EstimateGravity(const ClipBundle& b, const GravityConfig& config) {
  GravityEstimate g;
  if (config.use_bundle_up && !b.gravity_up.empty()) {
    Vec3 sum = Vec3::Zero();
    for (const Vec3& u : b.gravity_up) sum += u.normalized();
    if (sum.norm() > 1e-9) {
      g.up = sum.normalized();
      g.source = kGravityFromBundle;
      g.inlier_share = std::numeric_limits<double>::quiet_NaN();
      double sq = 0;
      for (const Vec3& u : b.gravity_up) {
        const double a = std::acos(std::clamp(u.normalized().dot(g.up), -1.0, 1.0));
        sq += a * a;
      }
      g.spread_deg = std::sqrt(sq / b.gravity_up.size()) * 180 / M_PI;
      return g;
    }
  }
  const int T = static_cast<int>(std::max(b.depth.size(), b.points.size()));
  for (int t = 0; t < T; ++t) {
    const cv::Mat points = PointMapAt(b, t);
    cv::Mat exclude = cv::Mat::zeros(points.rows, points.cols, CV_8U);
    cv::Mat hands = cv::Mat::zeros(points.rows, points.cols, CV_8U);
    for (const auto* masks : {&b.mask_object, &b.mask_hand_left, &b.mask_hand_right}) {
      if (static_cast<size_t>(t) < masks->size() && !(*masks)[t].empty()) exclude |= (*masks)[t];
    }
    for (const auto* masks : {&b.mask_hand_left, &b.mask_hand_right}) {
      if (static_cast<size_t>(t) < masks->size() && !(*masks)[t].empty()) hands |= (*masks)[t];
    }
    int n = 0;
    Vec3 above = MaskCentroid(hands, points, &n);
    if (n == 0) above = Vec3::Zero();  // no hands: the camera is above the support
    const auto plane = FitSupportPlane(points, exclude, above, config);
    if (!plane) continue;
    g.up = plane->normal;
    g.source = kGravityFromPlane;
    g.inlier_share = plane->inlier_share;
    g.frame = t;
    return g;
  }
  return g;
}

Mat3 UpToZ(const Vec3& up_camera) {
  const Vec3 z = up_camera.normalized();
  Vec3 x = Vec3::UnitX() - z * z.x();  // camera x, made horizontal
  if (x.norm() < 1e-6) x = Vec3::UnitZ() - z * z.z();
  x.normalize();
  const Vec3 y = z.cross(x);
  Mat3 r;
  r.row(0) = x.transpose();
  r.row(1) = y.transpose();
  r.row(2) = z.transpose();
  return r;
}

}  // namespace doasido::recon
