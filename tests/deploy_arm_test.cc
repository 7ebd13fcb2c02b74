// The UR3e model against its published DH definition, the IK against
// targets with known solutions, and the plan's reach report against a
// trajectory whose unreachable frames are known.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <random>
#include <set>

#include <unistd.h>

#include <gtest/gtest.h>

#include "deploy/arm_ik.h"
#include "deploy/plan.h"
#include "deploy/ur3e.h"
#include "eval/mug_mesh.h"
#include "retarget/scene/scene_builder.h"
#include "robot/embodiment.h"

namespace doasido::deploy {
namespace {

ArmQ RandomQ(std::mt19937& rng, double span = M_PI) {
  std::uniform_real_distribution<double> u(-span, span);
  ArmQ q;
  for (int i = 0; i < 6; ++i) q[i] = u(rng);
  return q;
}

// Independent DH product from the published table (not DhForward).
Mat4 ReferenceDh(const ArmQ& q) {
  const double d[6] = {0.15185, 0, 0, 0.13105, 0.08535, 0.0921};
  const double a[6] = {0, -0.24355, -0.2132, 0, 0, 0};
  const double alpha[6] = {M_PI / 2, 0, 0, M_PI / 2, -M_PI / 2, 0};
  Mat4 t = Mat4::Identity();
  for (int i = 0; i < 6; ++i) {
    Eigen::Affine3d step = Eigen::Affine3d::Identity();
    step.rotate(Eigen::AngleAxisd(q[i], Vec3::UnitZ()));
    step.translate(Vec3(0, 0, d[i]));
    step.translate(Vec3(a[i], 0, 0));
    step.rotate(Eigen::AngleAxisd(alpha[i], Vec3::UnitX()));
    t = t * step.matrix();
  }
  return t;
}

TEST(Ur3e, MjcfForwardKinematicsEqualsDh) {
  retarget::ModelPtr model = retarget::CompileMjcfText(Ur3eMjcf(), "ur3e");
  retarget::DataPtr data = retarget::MakeData(model.get());
  const int flange = retarget::NameToId(model.get(), mjOBJ_BODY, "ur3e_flange");
  ASSERT_GE(flange, 0);
  ASSERT_EQ(model->nq, 6);
  std::mt19937 rng(1);
  double worst_p = 0, worst_r = 0;
  for (int n = 0; n < 100; ++n) {
    const ArmQ q = RandomQ(rng, 2 * M_PI);
    for (int i = 0; i < 6; ++i) data->qpos[i] = q[i];
    mj_kinematics(model.get(), data.get());
    const Mat4 ref = ReferenceDh(q);
    const Vec3 p(data->xpos[3 * flange], data->xpos[3 * flange + 1], data->xpos[3 * flange + 2]);
    Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> r(data->xmat + 9 * flange);
    worst_p = std::max(worst_p, (p - ref.topRightCorner<3, 1>()).norm());
    worst_r = std::max(worst_r, (Mat3(r) - Mat3(ref.topLeftCorner<3, 3>())).norm());
    // The templated DH used by the IK agrees too.
    worst_p = std::max(worst_p, (DhForwardPose(q).t - ref.topRightCorner<3, 1>()).norm());
  }
  std::printf("MJCF vs DH at 100 configurations: worst %.2e m, rotation %.2e\n", worst_p, worst_r);
  EXPECT_LT(worst_p, 1e-6);
  EXPECT_LT(worst_r, 1e-6);
  // Published reach: the flange of the stretched arm is |a2| + |a3| + ... away.
  const Pose zero = DhForwardPose(ArmQ::Zero());
  EXPECT_NEAR(zero.t.x(), -(0.24355 + 0.2132), 1e-9);
}

TEST(Ur3e, JointLimitsAndSpeedsInModel) {
  retarget::ModelPtr model = retarget::CompileMjcfText(Ur3eMjcf(), "ur3e");
  const ArmLimits l = Ur3eLimits();
  for (int i = 0; i < 6; ++i) {
    EXPECT_TRUE(model->jnt_limited[i]);
    EXPECT_NEAR(model->jnt_range[2 * i], -2 * M_PI, 1e-9);
    EXPECT_NEAR(model->jnt_range[2 * i + 1], 2 * M_PI, 1e-9);
    EXPECT_NEAR(l.max_speed[i], i < 3 ? M_PI : 2 * M_PI, 1e-12);
    EXPECT_EQ(model->geom_type[i + 1], mjGEOM_CAPSULE);
  }
}

TEST(Ur3e, HandMountedOnFlangeLeftAndRight) {
  for (const char* name : {"sharpa_right", "sharpa_left"}) {
    const retarget::Embodiment e = retarget::FindEmbodiment(name, {});
    const Pose base{Quat(Eigen::AngleAxisd(0.3, Vec3::UnitZ())), Vec3(0.1, -0.2, 0.05)};
    const ArmHandModel arm = BuildArmHandModel(e, base);
    const mjModel* m = arm.model.get();
    EXPECT_EQ(arm.hand_joints.size(), 22u) << name;
    retarget::DataPtr d = retarget::MakeData(m);
    std::mt19937 rng(2);
    const ArmQ q = RandomQ(rng);
    for (int i = 0; i < 6; ++i) d->qpos[arm.arm_qpos[i]] = q[i];
    mj_kinematics(m, d.get());
    // The hand frame is the flange turned by the canonical mount, and the
    // flange is the DH pose in the placed base frame.
    const int frame = retarget::NameToId(m, mjOBJ_BODY, "doasido_hand_frame");
    const Pose flange = base * DhForwardPose(q);
    const Vec3 p(d->xpos[3 * frame], d->xpos[3 * frame + 1], d->xpos[3 * frame + 2]);
    Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> r(d->xmat + 9 * frame);
    EXPECT_LT((p - flange.t).norm(), 1e-9) << name;
    EXPECT_LT((Mat3(r) - flange.R() * arm.mount).norm(), 1e-9) << name;
  }
}

TEST(ArmIk, ReachesRandomReachablePoses) {
  ArmIk ik;
  std::mt19937 rng(3);
  int reached = 0, worst_starts = 0;
  double worst_p = 0, worst_r = 0;
  const ArmQ home(0, -M_PI / 2, M_PI / 2, -M_PI / 2, -M_PI / 2, 0);
  for (int n = 0; n < 1000; ++n) {
    const Pose target = DhForwardPose(RandomQ(rng));
    const IkResult r = ik.Solve(target, home);
    // Independent check of the answer by the reference DH product.
    const Mat4 got = ReferenceDh(r.q);
    const double pe = (got.topRightCorner<3, 1>() - target.t).norm();
    const double re = RotationAngle(Quat(Mat3(got.topLeftCorner<3, 3>())), target.q);
    reached += pe < 1e-3 && re < 0.01;
    worst_p = std::max(worst_p, pe);
    worst_r = std::max(worst_r, re);
    worst_starts = std::max(worst_starts, r.starts);
    for (int i = 0; i < 6; ++i) {
      EXPECT_GE(r.q[i], -2 * M_PI);
      EXPECT_LE(r.q[i], 2 * M_PI);
    }
  }
  std::printf("IK: %d/1000 reached, worst %.2e m, %.2e rad, at most %d starts\n", reached, worst_p,
              worst_r, worst_starts);
  EXPECT_EQ(reached, 1000);
}

// Wrist poses from a smooth joint path, so every frame has a known IK
// answer, except frames 20..29, lifted 1 m (beyond the 0.5 m reach).
retarget::HandTrajectory PathWithGap(Pose* centre_out) {
  retarget::HandTrajectory t;
  t.embodiment = "sharpa_right";
  t.fps = 50;
  t.qpos_names = {"doasido_wrist_x",  "doasido_wrist_y",  "doasido_wrist_z",
                  "doasido_wrist_rx", "doasido_wrist_ry", "doasido_wrist_rz"};
  const ArmQ home(0.3, -1.9, 1.7, -1.4, -1.5, 0.2);
  Vec3 centre = Vec3::Zero();
  for (int k = 0; k < 60; ++k) {
    ArmQ q = home;
    for (int i = 0; i < 6; ++i) q[i] += 0.15 * std::sin(2 * M_PI * k / 60.0 + i);
    Pose w = DhForwardPose(q);
    if (k >= 20 && k < 30) w.t.z() += 1.0;
    const Vec3 e = w.R().eulerAngles(0, 1, 2);  // R = Rx Ry Rz
    Eigen::VectorXd v(6);
    v << w.t, e;
    t.qpos.push_back(v);
    t.valid.push_back(true);
    t.fingertip_error.push_back(0);
    centre += w.t;
  }
  centre /= 60;
  *centre_out = {Quat::Identity(), centre};
  return t;
}

// No search, and the placement that maps PathWithGap's poses onto themselves.
PlanConfig IdentityPlacement(const Pose& centre) {
  PlanConfig config;
  config.workspace.x = centre.t.x();
  config.workspace.y = centre.t.y();
  config.workspace.yaw_steps = 1;
  config.workspace.offset_steps = 1;
  config.home = {0.3, -1.9, 1.7, -1.4, -1.5, 0.2};
  config.wrist_smoothing.cutoff_hz = 0;  // the exact path (deploy_wrist_smoothing_test smooths)
  return config;
}

TEST(Plan, UnreachableFramesReportedWithTimes) {
  Pose centre;
  const retarget::HandTrajectory t = PathWithGap(&centre);
  const PlanConfig config = IdentityPlacement(centre);  // the path is in the base frame
  const Plan plan = MakePlan(t, retarget::FindEmbodiment("sharpa_right", {}), config);
  ASSERT_EQ(plan.position_error.size(), 60u);  // one IK per trajectory frame
  EXPECT_FALSE(plan.ok);
  std::set<int> frames;
  for (const FrameIssue& u : plan.unreachable) {
    frames.insert(u.frame);
    EXPECT_NEAR(u.time, u.frame / 50.0, 1e-12);
    EXPECT_GT(u.value, 0.4);  // ~1 m less the arm's reach toward it
  }
  std::set<int> expected;
  for (int k = 20; k < 30; ++k) expected.insert(k);
  EXPECT_EQ(frames, expected);
  // Reachable frames are solved to tolerance.
  for (int k = 0; k < 60; ++k) {
    if (k >= 20 && k < 30) continue;
    EXPECT_LT(plan.position_error[k], 1e-3) << k;
    EXPECT_LT(plan.rotation_error[k], 0.01) << k;
  }
  EXPECT_EQ(plan.hand_joints.size(), 22u);
}

TEST(Plan, ReachablePathPassesAndFasterPathIsSlowedDown) {
  Pose centre;
  retarget::HandTrajectory t = PathWithGap(&centre);
  for (int k = 20; k < 30; ++k) t.qpos[k][2] -= 1.0;  // close the gap
  PlanConfig config = IdentityPlacement(centre);
  const retarget::Embodiment e = retarget::FindEmbodiment("sharpa_right", {});
  const Plan plan = MakePlan(t, e, config);
  EXPECT_TRUE(plan.ok) << plan.unreachable.size() << " unreachable, " << plan.too_fast.size()
                       << " too fast";
  // The same path ten times faster: 0.15 rad amplitude over 0.12 s exceeds
  // 180 deg/s on the big joints (and 5 rad/s^2 many times over); the
  // re-timing slows it down until it passes, commands still 2 ms apart.
  t.fps = 500;
  config.rate_hz = 500;
  const Plan fast = MakePlan(t, e, config);
  EXPECT_TRUE(fast.unreachable.empty());
  EXPECT_TRUE(fast.ok) << fast.too_fast.size() << " too fast, " << fast.over_acceleration.size() << " too abrupt";
  EXPECT_GT(fast.slowdown, 3.0);
  EXPECT_GT(fast.slowdown, 5 * plan.slowdown);
  for (size_t k = 0; k < fast.times.size(); ++k) EXPECT_NEAR(fast.times[k], k / 500.0, 1e-12);
}

// The replay measures the object against the trajectory: a mug the hand
// never touches stays where the scene put it, so against constant poses the
// error is ~0, and against poses that claim it slid 0.2 m along x the mean
// error is the mean claimed displacement, 0.1 m.
TEST(Plan, ReplayMeasuresObjectError) {
  Pose centre;
  retarget::HandTrajectory t = PathWithGap(&centre);
  for (int k = 20; k < 30; ++k) t.qpos[k][2] -= 1.0;
  const Vec3 away = -Vec3(centre.t.x(), centre.t.y(), 0).normalized() * 0.35;
  const Pose mug_pose{Quat::Identity(), away};
  const auto dir = std::filesystem::temp_directory_path() / ("replay_" + std::to_string(getpid()));
  retarget::SceneConfig scene_config;
  const retarget::ObjectScene scene =
      retarget::BuildObjectScene(retarget::MakeMug(), mug_pose, scene_config, dir);
  std::ifstream in(scene.xml_path);
  const std::string xml((std::istreambuf_iterator<char>(in)), {});
  PlanConfig config = IdentityPlacement(centre);
  const retarget::Embodiment e = retarget::FindEmbodiment("sharpa_right", {});
  Plan plan = MakePlan(t, e, config);
  ASSERT_TRUE(plan.ok);
  t.object_poses.assign(t.qpos.size(), scene.pose);
  ReplayPlan(plan, t, e, xml, dir);
  ASSERT_TRUE(plan.replay.ran);
  EXPECT_LT(plan.replay.object_position_error_max, 0.003);
  EXPECT_LT(plan.replay.object_rotation_error_max, 0.02);
  EXPECT_TRUE(plan.replay.success);
  for (size_t k = 0; k < t.qpos.size(); ++k) {
    t.object_poses[k].t.x() += 0.2 * k / (t.qpos.size() - 1.0);
  }
  plan.replay = {};
  ReplayPlan(plan, t, e, xml, dir);
  std::filesystem::remove_all(dir);
  // Measured at each command's trajectory time (the time map): the claimed
  // displacement there, averaged over the commands of the path.
  double claimed = 0;
  const size_t first = plan.lead_in, end = plan.arm.size() - plan.lead_out;
  for (size_t k = first; k < end; ++k) claimed += 0.2 * plan.source_times[k] * t.fps / (t.qpos.size() - 1.0);
  claimed /= end - first;
  EXPECT_NEAR(plan.replay.object_position_error_mean, claimed, 0.005);
  EXPECT_NEAR(plan.replay.object_position_error_max, 0.2, 0.005);
  // The flange follows the wrist path: IK within 1 mm at the frames, the
  // spline between them.
  ASSERT_EQ(plan.replay.wrist_position_error.size(), end - first);
  EXPECT_LT(plan.replay.wrist_position_error_max, 0.005);
  EXPECT_LT(plan.replay.wrist_rotation_error_max, 0.02);
}

// The lead-in ends coming straight down onto the first frame: a command
// whose flange is approach_height above the first wrist, then a descent
// along the vertical lasting at least approach_height / approach_speed.
TEST(Plan, TheLeadInComesDownOntoTheFirstFrame) {
  Pose centre;
  retarget::HandTrajectory t = PathWithGap(&centre);
  for (int k = 20; k < 30; ++k) t.qpos[k][2] -= 1.0;
  PlanConfig config = IdentityPlacement(centre);
  const Plan plan = MakePlan(t, retarget::FindEmbodiment("sharpa_right", {}), config);
  ASSERT_TRUE(plan.ok);
  const Pose base = plan.placement.world_to_base.Inverse();
  const Pose first = WristPose(t, 0);
  const auto flange = [&](int k) { return (base * DhForwardPose(plan.arm[k])).t; };
  int above = -1;
  for (int k = 0; k < plan.lead_in && above < 0; ++k) {
    if ((flange(k) - (first.t + Vec3(0, 0, config.approach_height))).norm() < 0.002) above = k;
  }
  ASSERT_GE(above, 0) << "no lead-in command 5 cm above the first frame";
  EXPECT_GE((plan.lead_in - above) / plan.rate_hz, config.approach_height / config.approach_speed - 0.03);
  for (int k = above; k <= plan.lead_in; ++k) {
    EXPECT_LT((flange(k) - first.t).head<2>().norm(), 0.003) << "command " << k << " leaves the vertical";
    if (k > above) {
      EXPECT_LE(flange(k).z(), flange(k - 1).z() + 1e-6) << "command " << k << " goes up";
    }
  }
  EXPECT_LT((flange(plan.lead_in) - first.t).norm(), 0.002);
}

// The floating-hand replay (the retargeting's wrist, driven here by the
// trajectory's wrist positions: the fixture has no controls) under the
// same time map as the arm's, on a path that needs a slowdown: both leave
// the untouched mug where it stands, both follow the wrist path, and both
// report every command of the path.
TEST(Plan, FloatingAndArmReplaysAgreeOnARetimedPath) {
  Pose centre;
  retarget::HandTrajectory t = PathWithGap(&centre);
  for (int k = 20; k < 30; ++k) t.qpos[k][2] -= 1.0;
  t.fps = 150;  // three times faster than the arm can follow
  const Vec3 away = -Vec3(centre.t.x(), centre.t.y(), 0).normalized() * 0.35;
  const auto dir = std::filesystem::temp_directory_path() / ("floating_" + std::to_string(getpid()));
  const retarget::ObjectScene scene =
      retarget::BuildObjectScene(retarget::MakeMug(), {Quat::Identity(), away}, retarget::SceneConfig{}, dir);
  std::ifstream in(scene.xml_path);
  const std::string xml((std::istreambuf_iterator<char>(in)), {});
  PlanConfig config = IdentityPlacement(centre);
  config.rate_hz = 150;
  const retarget::Embodiment e = retarget::FindEmbodiment("sharpa_right", {});
  Plan arm = MakePlan(t, e, config);
  ASSERT_TRUE(arm.ok);
  EXPECT_GT(arm.slowdown, 1.5);
  t.object_poses.assign(t.qpos.size(), scene.pose);
  Plan floating = arm;
  ReplayPlan(arm, t, e, xml, dir);
  ReplayPlan(floating, t, e, xml, dir, config.servo_omega, ReplayMount::kFloating);
  std::filesystem::remove_all(dir);
  const size_t path = arm.arm.size() - arm.lead_in - arm.lead_out;
  for (const Plan* p : {&arm, &floating}) {
    ASSERT_TRUE(p->replay.ran);
    EXPECT_TRUE(p->replay.success);
    EXPECT_LT(p->replay.object_position_error_max, 0.003);
    ASSERT_EQ(p->replay.wrist_position_error.size(), path);
    ASSERT_EQ(p->replay.hand_contacts.size(), path);
    ASSERT_EQ(p->replay.finger_error.size(), path);
    EXPECT_EQ(*std::max_element(p->replay.hand_contacts.begin(), p->replay.hand_contacts.end()), 0);
  }
  EXPECT_LT(arm.replay.wrist_position_error_max, 0.005);
  // The floating wrist is a PD at 40 rad/s without feed-forward (the
  // fixture has no controls that would lead it): it lags the moving target
  // by about 2 v / omega, v the wrist's speed under the time map, and sags
  // g / omega^2 = 6 mm.
  double speed = 0;
  for (size_t k = arm.lead_in; k + 1 < arm.arm.size() - arm.lead_out; ++k) {
    const double s0 = arm.source_times[k] * t.fps, s1 = arm.source_times[k + 1] * t.fps;
    const auto at = [&](double f) {
      const int i = std::min(static_cast<int>(f), static_cast<int>(t.qpos.size()) - 2);
      return Vec3((1 - (f - i)) * WristPose(t, i).t + (f - i) * WristPose(t, i + 1).t);
    };
    speed = std::max(speed, (at(s1) - at(s0)).norm() * arm.rate_hz);
  }
  EXPECT_GT(floating.replay.wrist_position_error_max, arm.replay.wrist_position_error_max);
  // On average within that bound; at the peaks (rotation and translation
  // lagging together) within three times it.
  const double lag = 2 * speed / config.servo_omega + 0.006;
  EXPECT_LT(floating.replay.wrist_position_error_mean, lag) << "wrist speed " << speed << " m/s";
  EXPECT_LT(floating.replay.wrist_position_error_max, 3 * lag) << "wrist speed " << speed << " m/s";
}

// Step 3b: the arm is planned on the floating hand's replayed wrist where
// the hand touches the object, on the trajectory's own wrist elsewhere. A
// mug the hand never touches leaves the path, and so the plan, as they
// were; a mug in the hand's way at the start moves the wrist near the
// frames where they touch (the floating replay's hand contacts) and
// nowhere farther than the smoothing window from them.
TEST(Plan, TheArmFollowsTheFloatingWristOnlyWhereTheHandTouches) {
  Pose centre;
  retarget::HandTrajectory t = PathWithGap(&centre);
  for (int k = 20; k < 30; ++k) t.qpos[k][2] -= 1.0;
  t.fps = 150;  // needs a slowdown
  PlanConfig config = IdentityPlacement(centre);
  config.rate_hz = 150;
  const retarget::Embodiment e = retarget::FindEmbodiment("sharpa_right", {});
  const Plan plan = MakePlan(t, e, config);
  ASSERT_TRUE(plan.ok);
  const auto dir = std::filesystem::temp_directory_path() / ("follow_" + std::to_string(getpid()));
  const auto scene_at = [&](const Vec3& where) {
    const retarget::ObjectScene scene =
        retarget::BuildObjectScene(retarget::MakeMug(), {Quat::Identity(), where}, retarget::SceneConfig{}, dir);
    t.object_poses.assign(t.qpos.size(), scene.pose);
    std::ifstream in(scene.xml_path);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  };
  const std::string untouched = scene_at(-Vec3(centre.t.x(), centre.t.y(), 0).normalized() * 0.35);
  const FollowedPlan same = PlanOnFloatingWrist(plan, t, e, config, untouched, dir);
  EXPECT_EQ(same.plan.wrist_path, kWristPathFloating);
  for (size_t f = 0; f < t.qpos.size(); ++f) EXPECT_EQ(same.trajectory.qpos[f], t.qpos[f]) << "frame " << f;
  ASSERT_EQ(same.plan.arm.size(), plan.arm.size());
  for (size_t k = 0; k < plan.arm.size(); ++k) EXPECT_LT((same.plan.arm[k] - plan.arm[k]).norm(), 1e-9);

  const Vec3 start = WristPose(t, 0).t;
  const std::string touched = scene_at(Vec3(start.x(), start.y(), start.z() - 0.08));
  Plan floating = plan;
  ReplayPlan(floating, t, e, touched, dir, config.servo_omega, ReplayMount::kFloating);
  const retarget::HandTrajectory followed =
      FloatingWristTrajectory(plan, t, e, touched, dir, config.servo_omega, config.follow_smoothing);
  std::filesystem::remove_all(dir);
  std::vector<double> touching;  // trajectory times of the commands with contacts
  for (size_t k = 0; k < floating.replay.hand_contacts.size(); ++k) {
    if (floating.replay.hand_contacts[k] > 0) touching.push_back(plan.source_times[k + plan.lead_in]);
  }
  ASSERT_FALSE(touching.empty()) << "the mug below the first wrist was not touched";
  double moved = 0;
  int far = 0;
  for (size_t f = 0; f < t.qpos.size(); ++f) {
    const double s = f / t.fps;
    double nearest = 1e9;
    for (double c : touching) nearest = std::min(nearest, std::abs(c - s));
    const double d = (WristPose(followed, f).t - WristPose(t, f).t).norm();
    moved = std::max(moved, d);
    if (nearest > config.follow_smoothing + 2 / t.fps) {
      EXPECT_EQ(d, 0) << "frame " << f << " far from contact";
      ++far;
    }
  }
  EXPECT_GT(far, 10) << "the hand touched the mug almost throughout";
  EXPECT_GT(moved, 0.0005);
}

TEST(Plan, JsonRoundTrip) {
  Pose centre;
  const retarget::HandTrajectory t = PathWithGap(&centre);
  PlanConfig config;
  config.workspace.yaw_steps = 2;
  config.workspace.offset_steps = 1;
  config.workspace.search_frames = 5;
  const Plan plan = MakePlan(t, retarget::FindEmbodiment("sharpa_right", {}), config);
  const auto path = std::filesystem::temp_directory_path() / ("plan_" + std::to_string(getpid()) + ".json");
  WritePlanJson(plan, path);
  const Plan back = ReadPlanJson(path);
  std::filesystem::remove(path);
  ASSERT_EQ(back.arm.size(), plan.arm.size());
  for (size_t k = 0; k < plan.arm.size(); ++k) {
    EXPECT_EQ(back.arm[k], plan.arm[k]);
    EXPECT_EQ(back.hand[k], plan.hand[k]);
  }
  EXPECT_EQ(back.unreachable.size(), plan.unreachable.size());
  EXPECT_EQ(back.ok, plan.ok);
  EXPECT_EQ(back.placement.candidates, 2);
  EXPECT_EQ(back.wrist_path, kWristPathTrajectory);
  Plan followed = plan;
  followed.wrist_path = kWristPathFloating;
  EXPECT_EQ(PlanFromJson(PlanToJson(followed), "followed").wrist_path, kWristPathFloating);
}

}  // namespace
}  // namespace doasido::deploy
