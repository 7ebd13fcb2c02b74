// Time scaling of arm plans (deploy/time_scaling.h, plan.h steps 3-4):
// trajectories made from joint paths with known speeds, so the slowdown
// they need is known; every check below recomputes the commands' speeds
// and accelerations itself by finite differences (not through the plan's
// own check).
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "deploy/plan.h"
#include "deploy/time_scaling.h"
#include "deploy/ur3e.h"
#include "robot/embodiment.h"
#include "tests/joint_path_trajectory.h"

namespace doasido::deploy {
namespace {

using testing::FromJointPath;

const ArmQ kStart(0.3, -1.9, 1.7, -1.4, -1.5, 0.2);

// The largest |speed| / limit and |acceleration| / limit over the commands,
// the arm at rest before the first and after the last.
std::pair<double, double> PeakRatios(const Plan& p) {
  const ArmLimits l = Ur3eLimits();
  const double r = p.rate_hz;
  const int n = static_cast<int>(p.arm.size());
  const auto q = [&](int k) { return p.arm[std::clamp(k, 0, n - 1)]; };
  double v = 0, a = 0;
  for (int k = 0; k <= n; ++k) {
    for (int j = 0; j < 6; ++j) {
      v = std::max(v, std::abs(q(k)[j] - q(k - 1)[j]) * r / l.max_speed[j]);
      a = std::max(a, std::abs(q(k + 1)[j] - 2 * q(k)[j] + q(k - 1)[j]) * r * r / l.max_acceleration[j]);
    }
  }
  return {v, a};
}

TEST(TimeScaling, SplineInterpolatesKnotsAndLines) {
  std::vector<double> knots;
  std::vector<Eigen::VectorXd> values, line;
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0, 1);
  for (int i = 0; i < 12; ++i) {
    knots.push_back(0.1 * i);
    values.push_back(Eigen::Vector2d(n(rng), n(rng)));
    line.push_back(Eigen::Vector2d(2 + 3 * knots.back(), -knots.back()));
  }
  const JointSpline s(knots, values), l(knots, line);
  for (int i = 0; i < 12; ++i) EXPECT_LT((s.Value(knots[i]) - values[i]).norm(), 1e-12);
  for (double x = 0; x <= 1.1; x += 0.013) {
    EXPECT_LT((l.Value(x) - Eigen::Vector2d(2 + 3 * x, -x)).norm(), 1e-12);
    EXPECT_LT((l.First(x) - Eigen::Vector2d(3, -1)).norm(), 1e-9);
    EXPECT_LT(l.Second(x).norm(), 1e-9);
  }
}

// The base joint turning at twice its speed limit for 1.5 s needs at least
// a 2x slowdown; the plan gets it and passes.
TEST(TimeScaling, TwiceTooFastGetsAtLeastTwiceSlowerAndPasses) {
  const double speed = 2 * Ur3eLimits().max_speed[0];
  const auto path = [&](double t) { ArmQ q = kStart; q[0] += speed * (t - 0.75); return q; };
  const retarget::HandTrajectory t = FromJointPath(path, 76, 50);  // 1.5 s
  const Plan plan = testing::PlanInBaseFrame(t, path(0));
  const auto [v, a] = PeakRatios(plan);
  std::printf("2x too fast: slowdown %.2f, %zu commands, peak speed %.3f and acceleration %.3f of the limits\n",
              plan.slowdown, plan.arm.size(), v, a);
  EXPECT_TRUE(plan.unreachable.empty());
  EXPECT_TRUE(plan.ok) << plan.too_fast.size() << " too fast, " << plan.over_acceleration.size() << " too abrupt";
  EXPECT_GE(plan.slowdown, 2.0);
  EXPECT_LT(plan.slowdown, 3.0);  // and not much more: 95% of the limit, ramps of ~0.6 s at 5 rad/s^2
  EXPECT_LE(v, 1.0);
  EXPECT_LE(a, 1.0);
  // The path is the one asked for: every command's flange on the wrist path.
  for (size_t k = plan.lead_in; k + plan.lead_out < plan.arm.size(); ++k) {
    const Pose want = DhForwardPose(path(plan.source_times[k]));
    EXPECT_LT((DhForwardPose(plan.arm[k]).t - want.t).norm(), 2e-3) << k;
  }
}

// Random smooth joint paths, some far beyond the limits: no command of any
// plan exceeds a speed or acceleration limit, and a path within them keeps
// (nearly) the video's pace.
TEST(TimeScaling, NoCommandExceedsALimit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> amp(0.05, 0.6), freq(0.2, 2.0), phase(0, 6.28);
  for (int trial = 0; trial < 6; ++trial) {
    ArmQ a, w, p;
    for (int j = 0; j < 6; ++j) a[j] = amp(rng), w[j] = freq(rng), p[j] = phase(rng);
    if (trial == 0) a *= 0.05, w *= 0.2;  // slow: within the limits at the video's pace
    const auto path = [&](double t) {
      ArmQ q = kStart;
      for (int j = 0; j < 6; ++j) q[j] += a[j] * std::sin(2 * M_PI * w[j] * t + p[j]);
      return q;
    };
    const retarget::HandTrajectory t = FromJointPath(path, 91, 30);  // 3 s
    const Plan plan = testing::PlanInBaseFrame(t, path(0));
    const auto [v, acc] = PeakRatios(plan);
    std::printf("trial %d: slowdown %.2f, peak speed %.3f, acceleration %.3f of the limits\n", trial, plan.slowdown,
                v, acc);
    EXPECT_TRUE(plan.ok) << trial;
    EXPECT_LE(v, 1.0) << trial;
    EXPECT_LE(acc, 1.0) << trial;
    EXPECT_GE(plan.slowdown, 1.0) << trial;
    if (trial == 0) {
      EXPECT_LT(plan.slowdown, 1.2);
    }
  }
}

// The time map runs from the trajectory's start to its end without going
// back; the first and last commands are at rest at home (lead moves), and
// without lead moves at the path's own ends.
TEST(TimeScaling, TimeMapMonotonicAndEndsAtRest) {
  const auto path = [](double t) { ArmQ q = kStart; q[1] += 0.4 * std::sin(3 * t); q[4] += t; return q; };
  const retarget::HandTrajectory t = FromJointPath(path, 61, 30);
  const ArmQ home(0, -1.5708, 1.5708, -1.5708, -1.5708, 0);
  for (bool leads : {true, false}) {
    PlanConfig config;
    config.lead_in = config.lead_out = leads;
    const Plan plan = testing::PlanInBaseFrame(t, leads ? home : path(0), config);
    ASSERT_TRUE(plan.ok);
    ASSERT_EQ(plan.source_times.size(), plan.arm.size());
    EXPECT_EQ(plan.source_times.front(), 0.0);
    EXPECT_NEAR(plan.source_times.back(), 2.0, 1e-12);
    for (size_t k = 1; k < plan.source_times.size(); ++k) {
      EXPECT_GE(plan.source_times[k], plan.source_times[k - 1]) << k;
      EXPECT_NEAR(plan.times[k], k / plan.rate_hz, 1e-12);
    }
    EXPECT_EQ(plan.lead_in > 0, leads);
    EXPECT_EQ(plan.lead_out > 0, leads);
    if (leads) {
      EXPECT_LT((plan.arm.front() - home).norm(), 1e-12);
      EXPECT_LT((plan.arm.back() - home).norm(), 1e-12);
    }
    // At rest: reaching the second command from rest within the
    // acceleration limit moves a joint at most a dt^2 (and the same at the end).
    const double dt = 1 / plan.rate_hz;
    const size_t n = plan.arm.size();
    for (int j = 0; j < 6; ++j) {
      const double bound = Ur3eLimits().max_acceleration[j] * dt * dt;
      EXPECT_LE(std::abs(plan.arm[1][j] - plan.arm[0][j]), bound) << j;
      EXPECT_LE(std::abs(plan.arm[n - 1][j] - plan.arm[n - 2][j]), bound) << j;
    }
  }
}

// Manipulability against the closed form for a UR arm, det J = s3 s5 a2 a3
// (c2 a2 + c23 a3 + s234 d5), zero at the elbow and wrist singularities.
TEST(TimeScaling, ManipulabilityMatchesClosedForm) {
  const DhParameters dh;
  const double a2 = dh.a[1], a3 = dh.a[2], d5 = dh.d[4];
  const double norm = std::abs(a2 * a3) * (std::abs(a2) + std::abs(a3) + d5);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-M_PI, M_PI);
  for (int n = 0; n < 200; ++n) {
    ArmQ q;
    for (int i = 0; i < 6; ++i) q[i] = u(rng);
    const double det = std::sin(q[2]) * std::sin(q[4]) * a2 * a3 *
                       (std::cos(q[1]) * a2 + std::cos(q[1] + q[2]) * a3 + std::sin(q[1] + q[2] + q[3]) * d5);
    EXPECT_NEAR(Manipulability(q), std::abs(det) / norm, 1e-9);
    EXPECT_LE(Manipulability(q), 1.0);
  }
  ArmQ elbow = kStart, wrist = kStart;
  elbow[2] = 0;
  wrist[4] = 0;
  EXPECT_LT(Manipulability(elbow), 1e-12);
  EXPECT_LT(Manipulability(wrist), 1e-12);
  EXPECT_GT(Manipulability(kStart), 0.1);
}

}  // namespace
}  // namespace doasido::deploy
