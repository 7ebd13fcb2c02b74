#include "deploy/wrist_smoothing.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "core/config_check.h"
#include "core/error.h"
#include "deploy/plan.h"
#include "robot/embodiment.h"

namespace doasido::deploy {
namespace {


// The kernel's weights w[0..r] (w[-i] = w[i]) for sigma frames, 3 sigma wide.
std::vector<double> GaussianKernel(double sigma_frames) {
  const int r = std::max(1, static_cast<int>(std::ceil(3 * sigma_frames)));
  std::vector<double> w(r + 1);
  for (int i = 0; i <= r; ++i) w[i] = std::exp(-0.5 * i * i / (sigma_frames * sigma_frames));
  return w;
}

// Zero-phase Gaussian low-pass of positions, ends point-reflected.
std::vector<Vec3> SmoothPositions(const std::vector<Vec3>& p, const std::vector<double>& w) {
  const int n = static_cast<int>(p.size()), r = static_cast<int>(w.size()) - 1;
  const auto at = [&](int i) -> Vec3 {
    if (i < 0) return 2 * p[0] - p[std::min(-i, n - 1)];
    if (i >= n) return 2 * p[n - 1] - p[std::max(2 * (n - 1) - i, 0)];
    return p[i];
  };
  std::vector<Vec3> out(n);
  for (int i = 0; i < n; ++i) {
    Vec3 sum = Vec3::Zero();
    double total = 0;
    for (int k = -r; k <= r; ++k) {
      sum += w[std::abs(k)] * at(i + k);
      total += w[std::abs(k)];
    }
    out[i] = sum / total;
  }
  return out;
}

// At each frame, the kernel-weighted mean of the neighbours' rotations
// relative to it, applied to it; the ends point-reflected as the
// positions' (q_0 q_k^-1 q_0 before the first frame).
std::vector<Quat> SmoothRotations(const std::vector<Quat>& q, const std::vector<double>& w) {
  const int n = static_cast<int>(q.size()), r = static_cast<int>(w.size()) - 1;
  const auto at = [&](int i) -> Quat {
    if (i < 0) return q[0] * q[std::min(-i, n - 1)].conjugate() * q[0];
    if (i >= n) return q[n - 1] * q[std::max(2 * (n - 1) - i, 0)].conjugate() * q[n - 1];
    return q[i];
  };
  std::vector<Quat> out(n);
  for (int i = 0; i < n; ++i) {
    Vec3 sum = Vec3::Zero();
    double total = 0;
    for (int k = -r; k <= r; ++k) {
      const Eigen::AngleAxisd rel(q[i].conjugate() * at(i + k));
      sum += w[std::abs(k)] * rel.angle() * rel.axis();
      total += w[std::abs(k)];
    }
    const Vec3 mean = sum / total;
    out[i] = (q[i] * Quat(Eigen::AngleAxisd(mean.norm(), mean.norm() > 0 ? Vec3(mean.normalized()) : Vec3::UnitX())))
                 .normalized();
  }
  return out;
}

// Rx(a) Ry(b) Rz(c) angles of `q` nearest `near` (the trajectory's own
// angles at that frame: the branch and the turns it uses).
Vec3 EulerNear(const Quat& q, const Vec3& near) {
  const Vec3 e = q.toRotationMatrix().eulerAngles(0, 1, 2);
  const Vec3 other(e[0] + std::numbers::pi, std::numbers::pi - e[1], e[2] + std::numbers::pi);
  const auto wrap = [&](Vec3 v) {
    for (int i = 0; i < 3; ++i) v[i] += 2 * std::numbers::pi * std::round((near[i] - v[i]) / (2 * std::numbers::pi));
    return v;
  };
  const Vec3 a = wrap(e), b = wrap(other);
  return (a - near).norm() <= (b - near).norm() ? a : b;
}

// A smooth scale s[i] <= need[i] (the largest share of frame i's
// correction its tolerance allows, 1 when all of it): the least of `need`
// within the kernel's reach (so every frame a kernel weight reaches is at
// most need[i]), then the kernel's weighted mean of that.
std::vector<double> BoundingScale(const std::vector<double>& need, const std::vector<double>& w) {
  const int n = static_cast<int>(need.size()), r = static_cast<int>(w.size()) - 1;
  std::vector<double> least(n), out(n);
  for (int i = 0; i < n; ++i) {
    least[i] = *std::min_element(need.begin() + std::max(0, i - r), need.begin() + std::min(n, i + r + 1));
  }
  for (int i = 0; i < n; ++i) {
    double sum = 0, total = 0;
    for (int k = std::max(0, i - r); k <= std::min(n - 1, i + r); ++k) {
      sum += w[std::abs(k - i)] * least[k];
      total += w[std::abs(k - i)];
    }
    out[i] = sum / total;
  }
  return out;
}

}  // namespace

void CheckConfig(const WristSmoothingConfig& c, const std::string& section) {
  RequireInRange(section, "cutoff_hz", c.cutoff_hz, 0, 100);
  RequireInRange(section, "tolerance", c.tolerance, 0, 0.1);
  RequireInRange(section, "rotation_tolerance", c.rotation_tolerance, 0, 1);
}

retarget::HandTrajectory SmoothWrist(const retarget::HandTrajectory& t, const WristSmoothingConfig& config,
                                     WristSmoothingReport* report) {
  WristSmoothingReport r{.cutoff_hz = config.cutoff_hz};
  const int n = static_cast<int>(t.qpos.size());
  if (!(config.cutoff_hz > 0) || (!t.object_poses.empty() && !config.with_object) || n < 3 || !(t.fps > 0)) {
    if (report) *report = r;
    return t;
  }
  std::vector<Pose> wrists;
  for (int f = 0; f < n; ++f) wrists.push_back(WristPose(t, f));
  const double sigma_frames = std::sqrt(std::log(2.0)) / (2 * std::numbers::pi * config.cutoff_hz) * t.fps;
  const std::vector<double> kernel = GaussianKernel(sigma_frames);
  std::vector<Vec3> positions;
  std::vector<Quat> rotations;
  for (const Pose& w : wrists) {
    positions.push_back(w.t);
    rotations.push_back(w.q);
  }
  const std::vector<Vec3> p = SmoothPositions(positions, kernel);
  const std::vector<Quat> q = SmoothRotations(rotations, kernel);
  // The corrections, each scaled down where it exceeds its tolerance by a
  // factor that itself varies smoothly (BoundingScale), so the bound adds
  // no kink of its own.
  std::vector<double> pos_need(n), rot_need(n);
  std::vector<Vec3> rot_step(n);
  for (int f = 0; f < n; ++f) {
    const double d = (p[f] - positions[f]).norm();
    const Eigen::AngleAxisd step(rotations[f].conjugate() * q[f]);
    rot_step[f] = step.angle() * step.axis();
    pos_need[f] = d > config.tolerance ? config.tolerance / d : 1.0;
    rot_need[f] = step.angle() > config.rotation_tolerance ? config.rotation_tolerance / step.angle() : 1.0;
    r.bounded_frames += pos_need[f] < 1 || rot_need[f] < 1;
  }
  const std::vector<double> pos_scale = BoundingScale(pos_need, kernel), rot_scale = BoundingScale(rot_need, kernel);
  std::vector<Pose> current(n);
  for (int f = 0; f < n; ++f) {
    const Vec3 v = rot_scale[f] * rot_step[f];
    const Quat turn = v.norm() > 0 ? Quat(Eigen::AngleAxisd(v.norm(), v.normalized())) : Quat::Identity();
    current[f] = {(rotations[f] * turn).normalized(), positions[f] + pos_scale[f] * (p[f] - positions[f])};
  }
  std::array<int, 6> column{};
  for (int i = 0; i < 6; ++i) {
    column[i] = static_cast<int>(std::find(t.qpos_names.begin(), t.qpos_names.end(), retarget::kWristJoints[i]) -
                                 t.qpos_names.begin());
  }
  retarget::HandTrajectory out = t;
  for (int f = 0; f < n; ++f) {
    const Pose& s = current[f];
    r.position_deviation_max = std::max(r.position_deviation_max, (s.t - wrists[f].t).norm());
    r.rotation_deviation_max = std::max(r.rotation_deviation_max, RotationAngle(s.q, wrists[f].q));
    Eigen::VectorXd& row = out.qpos[f];
    const Vec3 euler = EulerNear(s.q, Vec3(row[column[3]], row[column[4]], row[column[5]]));
    for (int i = 0; i < 3; ++i) {
      row[column[i]] = s.t[i];
      row[column[3 + i]] = euler[i];
    }
  }
  r.applied = true;
  if (report) *report = r;
  return out;
}

}  // namespace doasido::deploy
