#include "recon/align/visible_centroid.h"

#include <cmath>
#include <limits>

namespace doasido::recon {

VisibleHand& VisibleHand::operator+=(const VisibleHand& o) {
  mesh_sum += o.mesh_sum;
  map_sum += o.map_sum;
  rays += o.rays;
  hits += o.hits;
  return *this;
}

bool ValidPoint(const cv::Vec3f& p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]) && p[2] > 0;
}

cv::Mat PointMapAt(const ClipBundle& bundle, int t) {
  if (static_cast<size_t>(t) < bundle.points.size()) return bundle.points[t];
  const cv::Mat& depth = bundle.depth.at(static_cast<size_t>(t));
  const Camera cam = Camera::FromK(bundle.KAt(t), depth.cols, depth.rows);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cv::Mat points(depth.rows, depth.cols, CV_32FC3);
  for (int v = 0; v < depth.rows; ++v) {
    const float* d = depth.ptr<float>(v);
    cv::Vec3f* out = points.ptr<cv::Vec3f>(v);
    for (int u = 0; u < depth.cols; ++u) {
      if (!std::isfinite(d[u]) || d[u] <= 0) {
        out[u] = cv::Vec3f(nan, nan, nan);
        continue;
      }
      const Vec3 p = cam.Unproject(u, v, d[u]);
      out[u] = cv::Vec3f(static_cast<float>(p.x()), static_cast<float>(p.y()),
                         static_cast<float>(p.z()));
    }
  }
  return points;
}

VisibleHand CastHandMask(const RayCaster& hand, const Mat3& K, const cv::Mat& mask,
                         const cv::Mat& points) {
  const Mat3 k_inv = K.inverse();
  VisibleHand out;
  for (int v = 0; v < mask.rows; ++v) {
    const std::uint8_t* m = mask.ptr<std::uint8_t>(v);
    const cv::Vec3f* p = points.ptr<cv::Vec3f>(v);
    for (int u = 0; u < mask.cols; ++u) {
      if (!m[u]) continue;
      ++out.rays;
      if (!ValidPoint(p[u])) continue;
      const Vec3 dir = (k_inv * Vec3(u, v, 1)).normalized();
      const auto hit = hand.FirstHit(Vec3::Zero(), dir);
      if (!hit) continue;
      out.mesh_sum += *hit * dir;
      out.map_sum += Vec3(p[u][0], p[u][1], p[u][2]);
      ++out.hits;
    }
  }
  return out;
}

Vec3 MaskCentroid(const cv::Mat& mask, const cv::Mat& points, int* count) {
  Vec3 sum = Vec3::Zero();
  int n = 0;
  for (int v = 0; v < mask.rows; ++v) {
    const std::uint8_t* m = mask.ptr<std::uint8_t>(v);
    const cv::Vec3f* p = points.ptr<cv::Vec3f>(v);
    for (int u = 0; u < mask.cols; ++u) {
      if (!m[u] || !ValidPoint(p[u])) continue;
      sum += Vec3(p[u][0], p[u][1], p[u][2]);
      ++n;
    }
  }
  if (count) *count = n;
  return n ? Vec3(sum / n) : Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
}

}  // namespace doasido::recon
