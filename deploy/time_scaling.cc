#include "deploy/time_scaling.h"

#include <algorithm>
#include <cmath>

#include "core/config_check.h"
#include "core/error.h"

namespace doasido::deploy {
namespace {

using Eigen::VectorXd;

// Bisection steps for the largest feasible x at a grid point (x is known
// to within 2^-50 of its bound, far below anything a command resolves).
constexpr int kBisections = 50;
constexpr double kTiny = 1e-12;

// Quintic rest-to-rest profile 10 a^3 - 15 a^4 + 6 a^5: its peak speed is
// 15/8 and its peak acceleration 10/sqrt(3) (times distance / duration^n).
constexpr double kQuinticPeakSpeed = 1.875;
constexpr double kQuinticPeakAcceleration = 5.773502691896258;

struct GridPoint {
  double s = 0;
  VectorXd a, b;  // q'(s), q''(s)
};

// Adds the constraint lo_j <= a_j u + b_j x <= hi_j on u (for a given x)
// to [lo, hi]; false when it cannot hold for any u.
bool Constrain(double a, double b, double x, double limit, double& lo, double& hi) {
  if (std::abs(a) <= kTiny) return std::abs(b * x) <= limit;
  const double c1 = (-limit - b * x) / a, c2 = (limit - b * x) / a;
  lo = std::max(lo, std::min(c1, c2));
  hi = std::min(hi, std::max(c1, c2));
  return true;
}

// The interval of path accelerations u feasible at grid point g with path
// speed squared x, such that the next point's x stays within [0, next_hi]
// over a step `delta`; empty when lo > hi. The joint accelerations hold at
// both ends of the step (u is constant over it): at `next` they are
// a' u + b' (x + 2 delta u), still linear in (x, u). `next` null: the last
// point, no step.
std::pair<double, double> FeasibleU(const GridPoint& g, const GridPoint* next, double x, double next_hi,
                                    const VectorXd& amax) {
  double lo = -1e300, hi = 1e300;
  const double delta = next ? next->s - g.s : 0;
  if (next) {
    lo = -x / (2 * delta);
    hi = (next_hi - x) / (2 * delta);
  }
  for (int j = 0; j < g.a.size(); ++j) {
    if (!Constrain(g.a[j], g.b[j], x, amax[j], lo, hi)) return {1, 0};
    if (next && !Constrain(next->a[j] + 2 * delta * next->b[j], next->b[j], x, amax[j], lo, hi)) return {1, 0};
  }
  return {lo, hi};
}

bool Feasible(const GridPoint& g, const GridPoint* next, double x, double next_hi, const VectorXd& amax) {
  const auto [lo, hi] = FeasibleU(g, next, x, next_hi, amax);
  return lo <= hi + 1e-12 * std::max(1.0, std::abs(hi));
}

// The largest speed-feasible x at a grid point: sdot within the speed cap
// and every joint's speed within its limit.
double SpeedBound(const GridPoint& g, const VectorXd& vmax, double max_speedup) {
  double x = max_speedup * max_speedup;
  for (int j = 0; j < g.a.size(); ++j) {
    if (std::abs(g.a[j]) > kTiny) x = std::min(x, (vmax[j] / g.a[j]) * (vmax[j] / g.a[j]));
  }
  return x;
}

// Step 1 of time_scaling.h: the largest x from which the end is reachable.
std::vector<double> BackwardPass(const std::vector<GridPoint>& grid, const VectorXd& vmax, const VectorXd& amax,
                                 double max_speedup) {
  const size_t n = grid.size();
  std::vector<double> hi(n, 0.0);
  for (size_t i = n - 1; i-- > 0;) {
    const double top = SpeedBound(grid[i], vmax, max_speedup);
    if (Feasible(grid[i], &grid[i + 1], top, hi[i + 1], amax)) {
      hi[i] = top;
      continue;
    }
    double good = 0, bad = top;  // the feasible x form an interval [0, X]
    for (int k = 0; k < kBisections; ++k) {
      const double mid = 0.5 * (good + bad);
      (Feasible(grid[i], &grid[i + 1], mid, hi[i + 1], amax) ? good : bad) = mid;
    }
    hi[i] = good;
  }
  return hi;
}

// TimeMap::exceeded: where the path is slowest (the grid step that takes
// longest) and the joint that holds it back there (the one allowing the
// least path speed by its speed limit, or by its acceleration limit
// against the path's curvature).
TimeMap Exceeded(const std::vector<GridPoint>& grid, const std::vector<double>& t, const VectorXd& vmax,
                 const VectorXd& amax, double total, double length) {
  TimeMap out;
  out.exceeded = true;
  out.duration = total;
  out.slowdown = total / length;
  size_t slowest = 0;
  for (size_t i = 0; i + 1 < t.size(); ++i) {
    if (t[i + 1] - t[i] > t[slowest + 1] - t[slowest]) slowest = i;
  }
  const GridPoint& g = grid[slowest];
  out.slowest_s = g.s;
  double worst = -1;
  for (int j = 0; j < g.a.size(); ++j) {
    const double need = std::max(std::abs(g.a[j]) / vmax[j], std::sqrt(std::abs(g.b[j]) / amax[j]));
    if (need > worst) {
      worst = need;
      out.slowest_joint = j;
    }
  }
  return out;
}

}  // namespace

void CheckConfig(const TimeScalingConfig& c, const std::string& section) {
  RequireInRange(section, "margin", c.margin, 0.1, 1);
  RequireInRange(section, "max_speedup", c.max_speedup, 0.01, 100);
  RequireInRange(section, "grid_per_knot", c.grid_per_knot, 1, 64);
  RequireInRange(section, "attempts", c.attempts, 1, 20);
  RequireInRange(section, "max_slowdown", c.max_slowdown, 1, 10000);
}

JointSpline::JointSpline(std::vector<double> knots, std::vector<VectorXd> values)
    : knots_(std::move(knots)), values_(std::move(values)) {
  const size_t n = knots_.size();
  if (n == 0 || values_.size() != n) {
    throw Error("bad_trajectory", "a joint path needs as many values as knots, at least one", {.field = "qpos"});
  }
  for (size_t i = 1; i < n; ++i) {
    if (!(knots_[i] > knots_[i - 1])) throw Error("bad_trajectory", "path knots must increase", {.field = "fps"});
  }
  const VectorXd zero = VectorXd::Zero(values_[0].size());
  second_.assign(n, zero);
  if (n < 3) return;
  // Natural spline: second derivatives M with M_0 = M_{n-1} = 0, the
  // tridiagonal system solved by the Thomas algorithm, all components at once.
  std::vector<double> diag(n, 1.0), upper(n, 0.0);
  std::vector<VectorXd> rhs(n, zero);
  for (size_t i = 1; i + 1 < n; ++i) {
    const double h0 = knots_[i] - knots_[i - 1], h1 = knots_[i + 1] - knots_[i];
    const double lower = h0;
    diag[i] = 2 * (h0 + h1) - lower * upper[i - 1];
    upper[i] = h1 / diag[i];
    rhs[i] = (6 * ((values_[i + 1] - values_[i]) / h1 - (values_[i] - values_[i - 1]) / h0) - lower * rhs[i - 1]) /
             diag[i];
  }
  for (size_t i = n - 2; i >= 1; --i) second_[i] = rhs[i] - upper[i] * second_[i + 1];
}

size_t JointSpline::Segment(double s) const {
  if (knots_.size() < 2) return 0;
  const auto it = std::upper_bound(knots_.begin(), knots_.end(), s);
  const size_t i = it == knots_.begin() ? 0 : static_cast<size_t>(it - knots_.begin()) - 1;
  return std::min(i, knots_.size() - 2);
}

VectorXd JointSpline::Value(double s) const {
  if (knots_.size() == 1) return values_[0];
  const size_t i = Segment(s);
  const double h = knots_[i + 1] - knots_[i];
  const double a = (knots_[i + 1] - s) / h, b = (s - knots_[i]) / h;
  return a * values_[i] + b * values_[i + 1] +
         ((a * a * a - a) * second_[i] + (b * b * b - b) * second_[i + 1]) * (h * h / 6);
}

VectorXd JointSpline::First(double s) const {
  if (knots_.size() == 1) return VectorXd::Zero(values_[0].size());
  const size_t i = Segment(s);
  const double h = knots_[i + 1] - knots_[i];
  const double a = (knots_[i + 1] - s) / h, b = (s - knots_[i]) / h;
  return (values_[i + 1] - values_[i]) / h - (3 * a * a - 1) / 6 * h * second_[i] +
         (3 * b * b - 1) / 6 * h * second_[i + 1];
}

VectorXd JointSpline::Second(double s) const {
  if (knots_.size() == 1) return VectorXd::Zero(values_[0].size());
  const size_t i = Segment(s);
  const double h = knots_[i + 1] - knots_[i];
  const double a = (knots_[i + 1] - s) / h, b = (s - knots_[i]) / h;
  return a * second_[i] + b * second_[i + 1];
}

TimeMap RetimePath(const JointSpline& path, const VectorXd& max_speed, const VectorXd& max_acceleration,
                   double rate, const TimeScalingConfig& config, double margin) {
  if (max_speed.size() != path.dims() || max_acceleration.size() != path.dims()) {
    throw Error("bad_trajectory", "joint limits do not match the path's joints", {.field = "qpos"});
  }
  TimeMap out;
  const double length = path.end() - path.begin();
  if (!(length > 0)) {
    out.s = {path.begin()};
    return out;
  }
  // Grid: every knot interval (the trajectory's frames) split grid_per_knot times.
  std::vector<GridPoint> grid;
  const int segments = config.grid_per_knot * path.intervals();
  for (int i = 0; i <= segments; ++i) {
    const double s = path.begin() + length * i / segments;
    grid.push_back({s, path.First(s), path.Second(s)});
  }
  const VectorXd vmax = margin * max_speed, amax = margin * max_acceleration;
  const std::vector<double> hi = BackwardPass(grid, vmax, amax, config.max_speedup);
  // Step 2: forward, as fast as step 1's bounds allow.
  const size_t n = grid.size();
  std::vector<double> x(n, 0.0), u(n, 0.0), t(n, 0.0);
  for (size_t i = 0; i + 1 < n; ++i) {
    const double delta = grid[i + 1].s - grid[i].s;
    const auto [lo, up] = FeasibleU(grid[i], &grid[i + 1], x[i], hi[i + 1], amax);
    (void)lo;
    x[i + 1] = std::clamp(x[i] + 2 * delta * up, 0.0, hi[i + 1]);
    u[i] = (x[i + 1] - x[i]) / (2 * delta);
    const double speed_sum = std::sqrt(x[i]) + std::sqrt(x[i + 1]);
    t[i + 1] = t[i] + 2 * delta / std::max(speed_sum, 1e-9);
  }
  const double total = t.back();
  if (total > config.max_slowdown * length) return Exceeded(grid, t, vmax, amax, total, length);
  // s(t) at the command times: sdot = sqrt(x_i) + u_i tau within a step.
  const int last = static_cast<int>(std::ceil(total * rate - 1e-9));
  size_t i = 0;
  for (int k = 0; k <= last; ++k) {
    const double time = k / rate;
    if (time >= total) {
      out.s.push_back(path.end());
      continue;
    }
    while (i + 2 < n && t[i + 1] <= time) ++i;
    const double tau = time - t[i];
    const double s = grid[i].s + std::sqrt(x[i]) * tau + 0.5 * u[i] * tau * tau;
    out.s.push_back(std::clamp(s, grid[i].s, grid[i + 1].s));
  }
  for (size_t k = 1; k < out.s.size(); ++k) out.s[k] = std::max(out.s[k], out.s[k - 1]);
  out.duration = last / rate;
  out.slowdown = out.duration / length;
  return out;
}

int RestToRestIntervals(const VectorXd& from, const VectorXd& to, const VectorXd& max_speed,
                        const VectorXd& max_acceleration, double rate, double margin) {
  double duration = 0;
  for (int j = 0; j < from.size(); ++j) {
    const double d = std::abs(to[j] - from[j]);
    duration = std::max({duration, kQuinticPeakSpeed * d / (margin * max_speed[j]),
                         std::sqrt(kQuinticPeakAcceleration * d / (margin * max_acceleration[j]))});
  }
  return static_cast<int>(std::ceil(duration * rate - 1e-9));
}

VectorXd RestToRestAt(const VectorXd& from, const VectorXd& to, double a) {
  a = std::clamp(a, 0.0, 1.0);
  const double p = a * a * a * (10 - 15 * a + 6 * a * a);
  return from + p * (to - from);
}

std::vector<LimitExcess> CheckCommandLimits(const std::vector<VectorXd>& q, double rate, const VectorXd& max_speed,
                                            const VectorXd& max_acceleration) {
  std::vector<LimitExcess> out;
  const int n = static_cast<int>(q.size());
  // At rest before the first command and after the last.
  const auto at = [&](int k) -> const VectorXd& { return q[std::clamp(k, 0, n - 1)]; };
  for (int k = 0; k < n; ++k) {
    LimitExcess speed{.command = k, .joint = -1}, accel{.command = k, .joint = -1, .acceleration = true};
    double worst_speed = 1.0, worst_accel = 1.0;
    for (int j = 0; j < max_speed.size(); ++j) {
      const double v = std::abs(at(k)[j] - at(k - 1)[j]) * rate;
      const double a = std::abs(at(k + 1)[j] - 2 * at(k)[j] + at(k - 1)[j]) * rate * rate;
      if (v / max_speed[j] > worst_speed) {
        worst_speed = v / max_speed[j];
        speed.joint = j;
        speed.value = v;
        speed.limit = max_speed[j];
      }
      if (a / max_acceleration[j] > worst_accel) {
        worst_accel = a / max_acceleration[j];
        accel.joint = j;
        accel.value = a;
        accel.limit = max_acceleration[j];
      }
    }
    if (speed.joint >= 0) out.push_back(speed);
    if (accel.joint >= 0) out.push_back(accel);
  }
  return out;
}

}  // namespace doasido::deploy
