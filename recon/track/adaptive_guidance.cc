#include "recon/track/adaptive_guidance.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/config_check.h"
#include "core/error.h"

namespace doasido::recon {
namespace {

constexpr double kPi = 3.14159265358979323846;

bool Inside(const cv::Mat& mask, const Vec2& p) {
  const int x = static_cast<int>(std::lround(p.x())), y = static_cast<int>(std::lround(p.y()));
  return x >= 0 && y >= 0 && x < mask.cols && y < mask.rows && mask.at<std::uint8_t>(y, x) != 0;
}

// `n` distinct pixels of the mask, uniformly at random.
std::vector<Vec2> DrawPixels(const cv::Mat& mask, int n, std::mt19937_64& rng) {
  std::vector<cv::Point> pixels;
  cv::findNonZero(mask, pixels);
  std::shuffle(pixels.begin(), pixels.end(), rng);
  pixels.resize(std::min<size_t>(pixels.size(), n));
  std::vector<Vec2> out;
  for (const cv::Point& p : pixels) out.emplace_back(p.x, p.y);
  return out;
}

}  // namespace

void CheckConfig(const AdaptiveGuidanceConfig& c, const std::string& section) {
  RequireInRange(section, "points", c.points, 2, 100000);
  RequireInRange(section, "floor", c.floor, 0, 1);
  RequireInRange(section, "offset", c.offset, 0, 1);
  RequireInRange(section, "slope_per_degree", c.slope_per_degree, 0, 1);
  RequireInRange(section, "min_points", c.min_points, 2, c.points);
  RequireInRange(section, "fallback", c.fallback, 0, 1);
}

RigidMotion2D FitRigid2D(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  if (a.size() != b.size() || a.size() < 2) {
    throw Error("bad_tracks", "a 2D rigid fit needs two matching sets of at least 2 points");
  }
  Vec2 ca = Vec2::Zero(), cb = Vec2::Zero();
  for (size_t i = 0; i < a.size(); ++i) {
    ca += a[i];
    cb += b[i];
  }
  ca /= a.size();
  cb /= b.size();
  Eigen::Matrix2d H = Eigen::Matrix2d::Zero();
  for (size_t i = 0; i < a.size(); ++i) H += (a[i] - ca) * (b[i] - cb).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix2d D = Eigen::Matrix2d::Identity();
  D(1, 1) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  const Eigen::Matrix2d R = svd.matrixV() * D * svd.matrixU().transpose();
  RigidMotion2D out;
  out.angle_deg = std::atan2(R(1, 0), R(0, 0)) * 180 / kPi;
  out.translation = cb - R * ca;
  return out;
}

double PoseGuidance(double dtheta_deg, const AdaptiveGuidanceConfig& c) {
  return std::max(c.floor, c.offset - c.slope_per_degree * std::abs(dtheta_deg));
}

PointFollower FollowPointTracks(const PointTracks& tracks, double radius_px) {
  return [tracks, radius_px](int k, const std::vector<Vec2>& points) {
    std::vector<PointFollow> out;
    const Eigen::Index T = tracks.x.cols();
    for (const Vec2& p : points) {
      PointFollow f{p, p, false};
      double best = radius_px;
      for (Eigen::Index n = 0; k + 1 < T && n < tracks.x.rows(); ++n) {
        if (!tracks.visible(n, k) || !tracks.visible(n, k + 1)) continue;
        const Vec2 at(tracks.x(n, k), tracks.y(n, k));
        const double d = (at - p).norm();
        if (d > best) continue;
        best = d;
        f.to = p + Vec2(tracks.x(n, k + 1), tracks.y(n, k + 1)) - at;
        f.found = true;
      }
      out.push_back(f);
    }
    return out;
  };
}

GuidanceEstimate EstimatePoseGuidance(const std::vector<cv::Mat>& masks,
                                      const PointFollower& follow,
                                      const AdaptiveGuidanceConfig& config) {
  const int T = static_cast<int>(masks.size());
  GuidanceEstimate out;
  out.alpha_p.assign(T, 0.0);
  out.dtheta_deg.assign(T, 0.0);
  out.points_kept.assign(T, 0);
  std::mt19937_64 rng(config.seed);
  for (int k = 1; k < T; ++k) {
    const cv::Mat& before = masks[k - 1];
    std::vector<Vec2> a, b;
    if (!before.empty() && !masks[k].empty()) {
      for (const PointFollow& p : follow(k - 1, DrawPixels(before, config.points, rng))) {
        if (p.found && Inside(masks[k], p.to)) {
          a.push_back(p.from);
          b.push_back(p.to);
        }
      }
    }
    out.points_kept[k] = static_cast<int>(a.size());
    if (static_cast<int>(a.size()) < config.min_points) {
      out.dtheta_deg[k] = std::numeric_limits<double>::quiet_NaN();
      out.alpha_p[k] = config.fallback;
      continue;
    }
    out.dtheta_deg[k] = FitRigid2D(a, b).angle_deg;
    out.alpha_p[k] = PoseGuidance(out.dtheta_deg[k], config);
  }
  return out;
}

}  // namespace doasido::recon
