#include "objects/object_scale.h"

#include <algorithm>
#include <cmath>

#include "objects/ceres_geometry.h"

namespace doasido::objects {
namespace {

// The signed distance of SurfaceDistance, for Ceres' Jets.
template <typename T>
T SignedDistance(const T q[3], const Vec3& size, const T& scale, bool cylinder) {
  using std::abs;
  T d[3];
  int n = 0;
  if (cylinder) {
    using std::sqrt;
    d[n++] = sqrt(q[0] * q[0] + q[2] * q[2] + T(1e-18)) - scale * T(size.x() / 2);
    d[n++] = abs(q[1]) - scale * T(size.y() / 2);
  } else {
    for (int k = 0; k < 3; ++k) d[n++] = abs(q[k]) - scale * T(size[k] / 2);
  }
  T outside_sq = T(0);
  bool outside = false;
  T inside = d[0];
  for (int k = 0; k < n; ++k) {
    if (d[k] > T(0)) {
      outside_sq += d[k] * d[k];
      outside = true;
    }
    if (d[k] > inside) inside = d[k];
  }
  using std::sqrt;
  return outside ? sqrt(outside_sq) : inside;
}

struct ContactResidual {
  template <typename T>
  bool operator()(const T* log_scale, T* r) const {
    using std::exp;
    const T s = exp(log_scale[0]);
    T p[3], q[3];
    for (int k = 0; k < 3; ++k) p[k] = T(f[k]) - s * T(t[k]);
    for (int k = 0; k < 3; ++k) q[k] = T(R(0, k)) * p[0] + T(R(1, k)) * p[1] + T(R(2, k)) * p[2];
    r[0] = SignedDistance(q, shape, s, cylinder) - T(offset);
    return true;
  }
  Mat3 R;
  Vec3 t, f, shape;
  bool cylinder;
  double offset;
};

double Residual(const UnitPose& pose, const FingertipContact& c, const Vec3& shape, bool cylinder,
                double scale, double offset) {
  const Vec3 q = pose.R.transpose() * (c.fingertip - scale * pose.t);
  return SurfaceDistance(q, shape * scale, cylinder) - offset;
}

}  // namespace

double SurfaceDistance(const Vec3& q, const Vec3& size, bool cylinder) {
  return SignedDistance<double>(q.data(), size, 1.0, cylinder);
}

ContactScale FitContactScale(const std::vector<UnitPose>& poses, const Vec3& shape, bool cylinder,
                             const std::vector<FingertipContact>& contacts, double start,
                             const ContactScaleConfig& config) {
  // The robust cost over a log grid: the basin where the fingertips lie on
  // the surface (a nearer, smaller box puts the same tips inside it, a
  // farther, larger one in front of it).
  const double c2 = config.robust_m * config.robust_m;
  auto cost = [&](double scale) {
    double sum = 0;
    for (const FingertipContact& c : contacts) {
      const double r = Residual(poses[c.pose], c, shape, cylinder, scale, config.fingertip_offset_m);
      sum += std::log1p(r * r / c2);
    }
    return sum;
  };
  constexpr int kSteps = 161;
  const double lo = std::log(start * config.search_min), hi = std::log(start * config.search_max);
  double best = start, best_cost = 1e300;
  for (int i = 0; i < kSteps; ++i) {
    const double s = std::exp(lo + (hi - lo) * i / (kSteps - 1));
    const double value = cost(s);
    if (value < best_cost) {
      best_cost = value;
      best = s;
    }
  }
  double log_scale = std::log(best);
  ceres::Problem problem;
  for (const FingertipContact& c : contacts) {
    const UnitPose& p = poses[c.pose];
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ContactResidual, 1, 1>(new ContactResidual{
                                 p.R, p.t, c.fingertip, shape, cylinder, config.fingertip_offset_m}),
                             new ceres::CauchyLoss(config.robust_m), &log_scale);
  }
  SolveToConvergence(problem);
  ContactScale out;
  out.scale = std::exp(log_scale);
  std::vector<double> residuals;
  for (const FingertipContact& c : contacts) {
    residuals.push_back(
        std::abs(Residual(poses[c.pose], c, shape, cylinder, out.scale, config.fingertip_offset_m)));
  }
  std::nth_element(residuals.begin(), residuals.begin() + residuals.size() / 2, residuals.end());
  out.residual_median_m = residuals.empty() ? 0 : residuals[residuals.size() / 2];
  return out;
}

}  // namespace doasido::objects
