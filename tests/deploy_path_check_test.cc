// The arm between the trajectory's frames (deploy/plan.h step 4's
// off_path check; deploy/arm_ik.h's closed-form branches and least-motion
// path): wrist paths made by forward kinematics of known joint paths, so
// every frame's answer and every branch is known; a jump between two of a
// pose's IK solutions put into a plan by hand; a base turned past its
// joint limit, where a jump cannot be avoided.
#include <cmath>
#include <functional>
#include <random>

#include <gtest/gtest.h>

#include "core/error.h"
#include "deploy/arm_ik.h"
#include "deploy/plan.h"
#include "deploy/time_scaling.h"
#include "robot/embodiment.h"
#include "tests/joint_path_trajectory.h"
#include "tests/test_util.h"

namespace doasido::deploy {
namespace {

using doasido::testing::FromJointPath;
using doasido::testing::PlanInBaseFrame;
using JointPath = std::function<ArmQ(double)>;  // joints at time t (s)

// A smooth working motion around a bent-elbow pose.
ArmQ Working(double t) {
  ArmQ q(0.3, -1.9, 1.7, -1.4, -1.5, 0.2);
  for (int i = 0; i < 6; ++i) q[i] += 0.25 * std::sin(0.8 * t + i);
  return q;
}

TEST(ArmIk, ClosedFormSolutionsReachThePoseOnEveryBranch) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-M_PI, M_PI);
  int found_own = 0;
  for (int n = 0; n < 200; ++n) {
    ArmQ q;
    for (int i = 0; i < 6; ++i) q[i] = u(rng);
    const Pose target = DhForwardPose(q);
    const std::vector<ArmQ> solutions = ClosedFormIk(target, q[5]);
    ASSERT_GE(solutions.size(), 1u) << n;
    ASSERT_LE(solutions.size(), 8u) << n;
    bool own = false;
    for (const ArmQ& s : solutions) {
      const Pose got = DhForwardPose(s);
      EXPECT_LT((got.t - target.t).norm(), 1e-9) << n;
      EXPECT_LT(RotationAngle(got.q, target.q), 1e-6) << n;
      ArmQ d = s - q;
      for (int i = 0; i < 6; ++i) d[i] = std::remainder(d[i], 2 * M_PI);
      own = own || d.cwiseAbs().maxCoeff() < 1e-7;
    }
    found_own += own;
  }
  EXPECT_EQ(found_own, 200);  // the joints the pose was made from are among them
  // Out of reach (1 m from the base, the UR3e reaches ~0.5 m): none.
  EXPECT_TRUE(ClosedFormIk({Quat::Identity(), Vec3(1.0, 0, 0.1)}, 0).empty());
}



// A fast random joint path (amplitudes up to 1.4 rad at up to 1.6 rad/s)
// on which the warm-started solve alone slid onto another branch at
// frames 75-77 and 101 (the IK before the closed-form branches).
ArmQ Sweeping(double t) {
  const ArmQ c(1.983, -0.239, -1.918, -1.272, 2.159, -1.671), a(1.031, 1.342, 1.116, 0.548, 1.349, 1.457);
  const ArmQ w(1.541, 1.571, 0.622, 0.857, 0.793, 1.272), phase(2.635, -2.955, -2.125, 1.524, 1.621, -0.995);
  ArmQ q;
  for (int i = 0; i < 6; ++i) q[i] = c[i] + a[i] * std::sin(w[i] * t + phase[i]);
  return q;
}

TEST(ArmIk, APathStaysOnTheBranchItWasMadeOn) {
  std::vector<Pose> targets;
  for (int k = 0; k < 300; ++k) targets.push_back(DhForwardPose(Sweeping(k / 30.0)));
  ArmIk ik;
  const std::vector<IkResult> path = ik.LeastMotionPath(targets, Sweeping(0));
  ASSERT_EQ(path.size(), targets.size());
  double worst = 0;
  int worst_frame = -1;
  for (int k = 0; k < 300; ++k) {
    ASSERT_TRUE(path[k].reached) << k;
    const double off = (path[k].q - Sweeping(k / 30.0)).cwiseAbs().maxCoeff();
    if (off > worst) {
      worst = off;
      worst_frame = k;
    }
  }
  std::printf("IK along the sweep: joints within %.2e rad of the path they were made from (frame %d)\n", worst,
              worst_frame);
  EXPECT_LT(worst, 0.01);  // another branch is >= 0.5 rad away in some joint
  // Frame by frame from the previous answer alone, the warm start slides
  // onto another branch here (what the check below must not let through).
  ArmQ q = Sweeping(0);
  double warm_worst = 0;
  for (int k = 0; k < 300; ++k) {
    q = ik.Solve(targets[k], q).q;
    ArmQ off = q - Sweeping(k / 30.0);
    for (int i = 0; i < 6; ++i) off[i] = std::remainder(off[i], 2 * M_PI);  // another branch, not a turn
    warm_worst = std::max(warm_worst, off.cwiseAbs().maxCoeff());
  }
  std::printf("warm-started frame by frame: %.2f rad off\n", warm_worst);
  EXPECT_GT(warm_worst, 0.5);
}

TEST(PathCheck, APlanOnOneBranchStaysOnTheWristPathBetweenFrames) {
  const Plan plan = PlanInBaseFrame(FromJointPath(Sweeping, 300, 30), Sweeping(0));
  const PathDeviation& d = plan.path_deviation;
  std::printf("sweep: slowdown %.2fx, between frames %.2f mm / %.4f rad, %zu runs off the path\n", plan.slowdown,
              1000 * d.position_max, d.rotation_max, d.off_path.size());
  ASSERT_TRUE(d.checked);
  EXPECT_TRUE(plan.unreachable.empty());
  EXPECT_TRUE(d.off_path.empty());
  EXPECT_LT(d.position_max, 0.003);
  EXPECT_LT(d.rotation_max, 0.02);
  EXPECT_TRUE(plan.ok);
}

// The joint path through each frame's IK answer, sampled at 50 Hz without
// re-timing (the time map the identity), as MakePlan's commands are.
Plan CommandsThrough(const std::vector<ArmQ>& frame_q, double fps) {
  const JointSpline spline = JointPathThroughFrames(frame_q, fps);
  const double end = (frame_q.size() - 1) / fps;
  Plan plan;
  for (int k = 0; k / 50.0 <= end + 1e-9; ++k) {
    plan.times.push_back(k / 50.0);
    plan.source_times.push_back(k / 50.0);
    plan.arm.push_back(spline.Value(k / 50.0));
  }
  return plan;
}

TEST(PathCheck, AJumpToAnotherBranchIsCaughtBetweenTheFramesItLiesBetween) {
  constexpr int kFrames = 60, kJump = 30;
  constexpr double kFps = 30;
  std::vector<Pose> wrists;
  std::vector<ArmQ> one_branch, jumping;
  for (int f = 0; f < kFrames; ++f) {
    const ArmQ q = Working(f / kFps);
    wrists.push_back(DhForwardPose(q));
    one_branch.push_back(q);
    // From frame kJump on, the pose's other elbow: the same flange, other joints.
    ArmQ other = q;
    for (const ArmQ& s : ClosedFormIk(wrists.back(), q[5])) {
      if (std::abs(std::remainder(s[2] + q[2], 2 * M_PI)) < 1e-6) other = s;  // q3 -> -q3
    }
    jumping.push_back(f < kJump ? q : other);
  }
  const double jump = (jumping[kJump] - jumping[kJump - 1]).cwiseAbs().maxCoeff();
  ASSERT_GT(jump, 1.0);  // the elbow flipped

  const PathCheckConfig config;
  const PathDeviation clean = CheckPathDeviation(CommandsThrough(one_branch, kFps), wrists, kFps, one_branch, config);
  EXPECT_TRUE(clean.off_path.empty());
  EXPECT_LT(clean.position_max, 0.001);

  const Plan plan = CommandsThrough(jumping, kFps);
  const PathDeviation d = CheckPathDeviation(plan, wrists, kFps, jumping, config);
  ASSERT_FALSE(d.off_path.empty());
  bool named = false;
  for (const OffPathSpan& s : d.off_path) {
    std::printf("off path: commands %d-%d, frames %d-%d, %.1f mm / %.3f rad, joint step %.2f rad\n",
                s.first_command, s.last_command, s.from_frame, s.to_frame, 1000 * s.position_deviation,
                s.rotation_deviation, s.joint_jump);
    // The spline rings a few frames either side of the jump, no further.
    EXPECT_GE(s.from_frame, kJump - 6);
    EXPECT_LE(s.to_frame, kJump + 6);
    EXPECT_NEAR(s.start_time, plan.times[s.first_command], 1e-12);
    named = named || (s.from_frame <= kJump - 1 && s.to_frame >= kJump && s.joint_jump == jump);
  }
  EXPECT_TRUE(named) << "no run between frames " << kJump - 1 << " and " << kJump << " with the jump";
  EXPECT_GT(d.position_max, 0.05);
  EXPECT_GT(d.OffPathCommands(), 0);
}

// The base turns 2.5 times (900 degrees) about its axis while the rest of
// the arm holds still: shoulder_pan spans 720 degrees (+-360), so wherever
// the path starts, a jump cannot be avoided before 720 degrees of the turn
// (to the other shoulder branch, or a turn back), and the check must name
// where the plan makes it.
TEST(PathCheck, ABaseTurnedPastItsLimitMustJumpAndFailsNamingTheFrames) {
  constexpr double kFps = 30, kTurnRate = 2.5 * 2 * M_PI / 10;  // 2.5 turns in 10 s
  const ArmQ bent(0, -1.9, 1.7, -1.4, -1.5, 0.2);
  const JointPath turning = [&](double t) { ArmQ q = bent; q[0] += kTurnRate * t; return q; };
  const Plan plan = PlanInBaseFrame(FromJointPath(turning, 300, kFps), bent);
  int limit_frame = 0;  // the first frame 720 degrees into the turn
  while (turning(limit_frame / kFps)[0] - bent[0] <= 4 * M_PI) ++limit_frame;
  EXPECT_TRUE(plan.unreachable.empty());  // every frame is reached, by some branch
  ASSERT_FALSE(plan.ok);
  const PathDeviation& d = plan.path_deviation;
  ASSERT_FALSE(d.off_path.empty());
  for (const OffPathSpan& s : d.off_path) {
    std::printf("turning base: off path between frames %d and %d (t %.2f-%.2f s): %.0f mm, joint step %.2f rad\n",
                s.from_frame, s.to_frame, s.start_time, s.end_time, 1000 * s.position_deviation, s.joint_jump);
    EXPECT_GT(s.joint_jump, 1.0);  // each run is a jump between branches, not the spline's wiggle
  }
  // No branch turns the base 720 degrees: the first jump comes at or before limit_frame.
  EXPECT_LE(d.off_path[0].from_frame, limit_frame);
  EXPECT_GT(d.position_max, 0.05);

  // The plan file keeps the check: counted, explained, read back.
  testing::TempDir dir;
  WritePlanJson(plan, dir / "plan.json");
  const Plan back = ReadPlanJson(dir / "plan.json");
  EXPECT_TRUE(back.path_deviation.checked);
  EXPECT_EQ(back.path_deviation.OffPathCommands(), d.OffPathCommands());
  EXPECT_EQ(back.path_deviation.off_path.size(), d.off_path.size());
  EXPECT_EQ(back.path_deviation.off_path[0].from_frame, d.off_path[0].from_frame);
  EXPECT_EQ(back.path_deviation.position_max, d.position_max);
  EXPECT_EQ(back.path_deviation.position_tolerance, PathCheckConfig{}.position_tolerance);
  EXPECT_FALSE(back.ok);
}

TEST(PathCheck, TheToleranceIsCheckedAtLoadAndOlderPlanFilesReadUnchecked) {
  PlanConfig config;
  config.path_check.position_tolerance = 0;
  EXPECT_THROW(CheckConfig(config, "deploy"), Error);
  config.path_check = {};
  config.path_check.rotation_tolerance = -1;
  try {
    CheckConfig(config, "deploy");
    ADD_FAILURE() << "a negative tolerance was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("deploy.path_check"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rotation_tolerance"), std::string::npos) << e.what();
  }
  // A plan file from before the check: no "path_deviation" member.
  Json j = PlanToJson(PlanInBaseFrame(FromJointPath(Working, 30, 30), Working(0)));
  ASSERT_TRUE(j.contains("path_deviation"));
  j.erase("path_deviation");
  const Plan old = PlanFromJson(j, "old.json");
  EXPECT_FALSE(old.path_deviation.checked);
  EXPECT_TRUE(old.path_deviation.off_path.empty());
}

}  // namespace
}  // namespace doasido::deploy
