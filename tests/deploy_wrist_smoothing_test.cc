// The wrist smoothing before planning (deploy/wrist_smoothing.h) on a wrist
// path with a known clean answer: a slow joint-space motion of the arm
// (every frame reachable, the flange pose its DH product), with and
// without noise of the size a wrist tracked from video has.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "core/error.h"
#include "deploy/arm_ik.h"
#include "deploy/plan.h"
#include "deploy/wrist_smoothing.h"
#include "robot/embodiment.h"

namespace doasido::deploy {
namespace {

const ArmQ kHome(0.3, -1.9, 1.7, -1.4, -1.5, 0.2);

Eigen::VectorXd Row(const Pose& w) {
  Eigen::VectorXd v(6);
  v << w.t, w.R().eulerAngles(0, 1, 2);  // R = Rx Ry Rz
  return v;
}

// 5 s at 30 fps of the arm swinging 0.3 rad per joint at 0.2 Hz around
// kHome, as floating-wrist poses; `noise_m` / `noise_rad` Gaussian noise
// per frame on the position and (about a random axis) the rotation.
retarget::HandTrajectory SlowPath(double noise_m, double noise_rad, std::vector<Pose>* clean = nullptr) {
  retarget::HandTrajectory t;
  t.embodiment = "sharpa_right";
  t.fps = 30;
  t.qpos_names.assign(std::begin(retarget::kWristJoints), std::end(retarget::kWristJoints));
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0, 1);
  for (int k = 0; k < 150; ++k) {
    ArmQ q = kHome;
    for (int i = 0; i < 6; ++i) q[i] += 0.3 * std::sin(2 * M_PI * 0.2 * k / t.fps + i);
    Pose w = DhForwardPose(q);
    if (clean) clean->push_back(w);
    w.t += noise_m * Vec3(g(rng), g(rng), g(rng));
    const Vec3 axis = Vec3(g(rng), g(rng), g(rng)).normalized();
    w.q = (w.q * Quat(Eigen::AngleAxisd(noise_rad * g(rng), axis))).normalized();
    t.qpos.push_back(Row(w));
    t.valid.push_back(true);
    t.fingertip_error.push_back(0);
  }
  return t;
}

PlanConfig Config(const retarget::HandTrajectory& t) {
  PlanConfig config;  // the path is in the base frame: the placement that keeps it there
  Vec3 centre = Vec3::Zero();
  for (int f = 0; f < static_cast<int>(t.qpos.size()); ++f) centre += WristPose(t, f).t;
  centre /= static_cast<double>(t.qpos.size());
  config.workspace.x = centre.x();
  config.workspace.y = centre.y();
  config.workspace.yaw_steps = 1;
  config.workspace.offset_steps = 1;
  config.home = {kHome[0], kHome[1], kHome[2], kHome[3], kHome[4], kHome[5]};
  return config;
}

// The arm's fastest joint along the path at the trajectory's own clock
// (IK per frame, warm-started), rad/s.
double PeakJointSpeed(const retarget::HandTrajectory& t) {
  ArmIk ik(IkConfig{});
  ArmQ q = kHome;
  double peak = 0;
  for (int f = 0; f < static_cast<int>(t.qpos.size()); ++f) {
    const ArmQ next = ik.Solve(WristPose(t, f), q).q;
    if (f > 0) peak = std::max(peak, (next - q).cwiseAbs().maxCoeff() * t.fps);
    q = next;
  }
  return peak;
}

double MaxPositionGap(const retarget::HandTrajectory& a, const retarget::HandTrajectory& b) {
  double gap = 0;
  for (int f = 0; f < static_cast<int>(a.qpos.size()); ++f) gap = std::max(gap, (WristPose(a, f).t - WristPose(b, f).t).norm());
  return gap;
}

double MaxRotationGap(const retarget::HandTrajectory& a, const retarget::HandTrajectory& b) {
  double gap = 0;
  for (int f = 0; f < static_cast<int>(a.qpos.size()); ++f) {
    gap = std::max(gap, RotationAngle(WristPose(a, f).q, WristPose(b, f).q));
  }
  return gap;
}

TEST(WristSmoothing, ANoisyPathIsSmoothedWithinTheToleranceAndPlansFaster) {
  std::vector<Pose> clean;
  const retarget::HandTrajectory noisy = SlowPath(0.003, 0.03, &clean);
  const WristSmoothingConfig config;
  WristSmoothingReport report;
  const retarget::HandTrajectory smooth = SmoothWrist(noisy, config, &report);
  ASSERT_TRUE(report.applied);
  // Never further from the recorded wrist than the tolerances, as measured
  // here and as reported.
  EXPECT_LE(MaxPositionGap(smooth, noisy), config.tolerance + 1e-9);
  EXPECT_LE(MaxRotationGap(smooth, noisy), config.rotation_tolerance + 1e-9);
  EXPECT_NEAR(report.position_deviation_max, MaxPositionGap(smooth, noisy), 1e-9);
  // Nearer the clean path than the noisy one is (the noise removed, not the motion).
  double before = 0, after = 0;
  for (size_t f = 0; f < clean.size(); ++f) {
    before += (WristPose(noisy, f).t - clean[f].t).squaredNorm();
    after += (WristPose(smooth, f).t - clean[f].t).squaredNorm();
  }
  std::printf("rms to the clean path: noisy %.2f mm, smoothed %.2f mm; largest move %.2f mm, %.3f rad\n",
              1000 * std::sqrt(before / clean.size()), 1000 * std::sqrt(after / clean.size()),
              1000 * report.position_deviation_max, report.rotation_deviation_max);
  EXPECT_LT(after, 0.5 * before);  // rms down by at least 29 %

  const double peak_noisy = PeakJointSpeed(noisy), peak_smooth = PeakJointSpeed(smooth);
  PlanConfig off = Config(noisy), on = Config(noisy);
  off.wrist_smoothing.cutoff_hz = 0;
  const retarget::Embodiment e = retarget::FindEmbodiment("sharpa_right", {});
  const Plan rough = MakePlan(noisy, e, off), planned = MakePlan(noisy, e, on);
  std::printf("peak joint speed at the video's clock %.2f -> %.2f rad/s; slowdown %.2fx -> %.2fx\n", peak_noisy,
              peak_smooth, rough.slowdown, planned.slowdown);
  EXPECT_LT(peak_smooth, 0.7 * peak_noisy);
  EXPECT_TRUE(planned.ok);
  EXPECT_LT(planned.slowdown, 0.8 * rough.slowdown);
  EXPECT_FALSE(rough.wrist_smoothing.applied);
  EXPECT_TRUE(planned.wrist_smoothing.applied);
}

TEST(WristSmoothing, ACleanPathIsKeptWithinAMillimetre) {
  const retarget::HandTrajectory clean = SlowPath(0, 0);
  WristSmoothingReport report;
  const retarget::HandTrajectory smooth = SmoothWrist(clean, {}, &report);
  ASSERT_TRUE(report.applied);
  EXPECT_EQ(report.bounded_frames, 0);
  EXPECT_LT(MaxPositionGap(smooth, clean), 0.001);
  EXPECT_LT(MaxRotationGap(smooth, clean), 0.01);
}

TEST(WristSmoothing, ATrajectoryWithAnObjectIsLeftAloneUnlessAsked) {
  retarget::HandTrajectory t = SlowPath(0.003, 0.03);
  t.object_poses.assign(t.qpos.size(), Pose{});
  WristSmoothingReport report;
  const retarget::HandTrajectory same = SmoothWrist(t, {}, &report);
  EXPECT_FALSE(report.applied);
  EXPECT_EQ(MaxPositionGap(same, t), 0.0);
  WristSmoothingConfig config;
  config.with_object = true;
  SmoothWrist(t, config, &report);
  EXPECT_TRUE(report.applied);
  EXPECT_GT(report.position_deviation_max, 0.001);
}

TEST(WristSmoothing, TheConfigIsCheckedAndThePlanFileKeepsTheReport) {
  PlanConfig config;
  config.wrist_smoothing.cutoff_hz = -1;
  try {
    CheckConfig(config, "deploy");
    ADD_FAILURE() << "a negative cut-off was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cutoff_hz"), std::string::npos) << e.what();
  }
  const retarget::HandTrajectory t = SlowPath(0.003, 0.03);
  const Plan plan = MakePlan(t, retarget::FindEmbodiment("sharpa_right", {}), Config(t));
  const Plan back = PlanFromJson(PlanToJson(plan), "plan.json");
  EXPECT_TRUE(back.wrist_smoothing.applied);
  EXPECT_DOUBLE_EQ(back.wrist_smoothing.position_deviation_max, plan.wrist_smoothing.position_deviation_max);
  EXPECT_EQ(back.wrist_smoothing.bounded_frames, plan.wrist_smoothing.bounded_frames);
}

}  // namespace
}  // namespace doasido::deploy
