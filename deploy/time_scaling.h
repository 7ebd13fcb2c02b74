// Time scaling: a joint path q(s), s the trajectory's own (video) time, is
// re-timed s = s(t) so that every joint stays within its speed and
// acceleration limits, as fast as the limits allow but never faster than
// the video, starting and ending at rest.
//
// The path is a natural cubic spline per joint through the knots (the
// trajectory's frames, where the arm IK was solved), so q'(s) and q''(s)
// exist everywhere. With x = sdot^2 and u = sddot, joint j's speed is
// |q'_j| sqrt(x) and its acceleration q'_j u + q''_j x, linear in (x, u).
// The re-timing is a time-optimal path parameterisation in the manner of
// TOPP-RA (Pham & Pham 2018), our own implementation: on a grid s_0..s_N
// (each knot interval split `grid_per_knot` times) with x_{i+1} = x_i +
// 2 (s_{i+1} - s_i) u_i,
//   1. backward: the largest x_i from which the end (x_N = 0) can still be
//      reached within the constraints (each a 2-variable LP, solved by
//      bisection on x over the interval of feasible u);
//   2. forward: from x_0 = 0, the largest feasible u_i that stays within
//      step 1's bounds.
// Between grid points the path speed follows sdot = sqrt(x_i) + u_i tau
// exactly, so s(t) at any command time is closed form. The constraints hold
// at the grid points; the limits are scaled by `margin` (< 1) to keep the
// spline's variation between them, and deploy/plan.h checks every command
// against the full limits by finite differences.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/config.h"

namespace doasido::deploy {

struct TimeScalingConfig {
  double margin = 0.95;      // fraction of the speed and acceleration limits aimed at
  double max_speedup = 1.0;  // path speed cap, times the video's (1: never faster than the video)
  int grid_per_knot = 2;     // grid points per knot interval
  int attempts = 4;          // re-timings with a smaller margin when a command still exceeds a limit
  // The longest re-timed path, times its own duration: beyond it the
  // re-timing makes no commands (TimeMap::exceeded). A joint path that
  // jumps between far-apart solutions (frames out of reach, where the IK
  // keeps its least-bad answer) can need a near-zero path speed, and its
  // commands would fill the memory (two arms placed out of reach: tens
  // of GB); real clips need up to ~20x.
  double max_slowdown = 100;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(TimeScalingConfig, margin, max_speedup, grid_per_knot,
                                                attempts, max_slowdown)
void CheckConfig(const TimeScalingConfig& c, const std::string& section);

// A natural cubic spline through (knots[i], values[i]); values are vectors
// of one size (one spline per component). Knots strictly increasing.
class JointSpline {
 public:
  JointSpline(std::vector<double> knots, std::vector<Eigen::VectorXd> values);
  Eigen::VectorXd Value(double s) const;
  Eigen::VectorXd First(double s) const;   // d/ds
  Eigen::VectorXd Second(double s) const;  // d2/ds2
  double begin() const { return knots_.front(); }
  double end() const { return knots_.back(); }
  int intervals() const { return static_cast<int>(knots_.size()) - 1; }
  int dims() const { return values_.empty() ? 0 : static_cast<int>(values_[0].size()); }

 private:
  size_t Segment(double s) const;
  std::vector<double> knots_;
  std::vector<Eigen::VectorXd> values_, second_;  // second: the spline's q'' at the knots
};

// The re-timing of one path: path time s at every command time k / rate.
struct TimeMap {
  std::vector<double> s;  // s[k] at t = k / rate; s.front() = begin, s.back() = end, non-decreasing
  double duration = 0;    // s of the re-timed path (the last command's time)
  double slowdown = 1;    // duration / (end - begin)
  // The re-timed path would last more than config.max_slowdown times the
  // path's: `s` is empty, duration and slowdown are what they would be,
  // and the path is slowest at path time slowest_s, held back by joint
  // slowest_joint (its speed or acceleration limit).
  bool exceeded = false;
  double slowest_s = 0;
  int slowest_joint = -1;
};

// Re-times `path` under per-joint limits (rad/s, rad/s^2; sizes = dims) at
// `rate` Hz commands, aiming at `margin` of the limits. Throws
// Error("bad_trajectory") for an empty path or limits of the wrong size.
TimeMap RetimePath(const JointSpline& path, const Eigen::VectorXd& max_speed,
                   const Eigen::VectorXd& max_acceleration, double rate, const TimeScalingConfig& config,
                   double margin);

// A rest-to-rest joint move from `from` to `to` (quintic, zero speed and
// acceleration at both ends) within `margin` of the limits, sampled at
// `rate` Hz: the number of command intervals it needs (0 when from == to).
int RestToRestIntervals(const Eigen::VectorXd& from, const Eigen::VectorXd& to, const Eigen::VectorXd& max_speed,
                        const Eigen::VectorXd& max_acceleration, double rate, double margin);
// The quintic's point at fraction `a` in [0, 1] of the move.
Eigen::VectorXd RestToRestAt(const Eigen::VectorXd& from, const Eigen::VectorXd& to, double a);

// The commands' finite-difference speeds and accelerations, the arm at rest
// before the first command and after the last: the first command whose
// joint exceeds a limit, per command (speed: (q_k - q_{k-1}) rate;
// acceleration: (q_{k+1} - 2 q_k + q_{k-1}) rate^2).
struct LimitExcess {
  int command = 0;
  int joint = 0;
  double value = 0;  // rad/s or rad/s^2 (absolute)
  double limit = 0;
  bool acceleration = false;
};
std::vector<LimitExcess> CheckCommandLimits(const std::vector<Eigen::VectorXd>& q, double rate,
                                            const Eigen::VectorXd& max_speed,
                                            const Eigen::VectorXd& max_acceleration);

}  // namespace doasido::deploy
