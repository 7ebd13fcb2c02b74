// `doasido deploy stream` and `deploy plan` through the built binary. The
// stream is recorded by Debian's lcm-logger (an independent process) on a
// loopback-only multicast URL (ttl=0) and read back with LCM's log reader.
#include <algorithm>
#include <cmath>
#include <csignal>
#include <functional>
#include <thread>

#include <unistd.h>

#include <gtest/gtest.h>

#include "deploy/bimanual.h"
#include "deploy/plan.h"
#include "deploy/stream.h"
#include "deploy/ur3e.h"
#include "robot/trajectory/format.h"
#include "tests/joint_path_trajectory.h"
#include "tests/test_util.h"
#include "tests/two_hand_episode.h"

namespace doasido {
namespace {

using testing::LoopbackLcmUrl;
using testing::RunDoasido;
using testing::Spawn;
using testing::WaitFor;
using testing::TempDir;

// A 10-s plan at 50 Hz with distinct values in every cell.
deploy::Plan TenSecondPlan(bool ok) {
  deploy::Plan p;
  p.rate_hz = 50;
  for (const char* n : deploy::Ur3eJointNames()) p.arm_joints.push_back(n);
  for (int h = 0; h < 22; ++h) p.hand_joints.push_back("j" + std::to_string(h));
  for (int k = 0; k < 500; ++k) {
    p.times.push_back(k / 50.0);
    p.source_times.push_back(k / 50.0);
    deploy::ArmQ q;
    for (int i = 0; i < 6; ++i) q[i] = 0.5 * std::sin(0.37 * k + i) + 1e-3 * i;
    p.arm.push_back(q);
    Eigen::VectorXd hand(22);
    for (int h = 0; h < 22; ++h) hand[h] = 0.01 * k + 0.1 * h + 1.0 / 3.0;
    p.hand.push_back(hand);
    p.position_error.push_back(0);
    p.rotation_error.push_back(0);
  }
  p.ok = ok;
  if (!ok) p.unreachable.push_back({.frame = 3, .time = 0.06, .value = 0.2, .limit = 0.1});
  return p;
}

void ExpectEqualsPlan(const std::vector<deploy::CommandRecord>& got, const deploy::Plan& plan) {
  for (const deploy::CommandRecord& r : got) {
    ASSERT_GE(r.sequence, 0);
    ASSERT_LT(r.sequence, static_cast<int64_t>(plan.arm.size()));
    const size_t k = static_cast<size_t>(r.sequence);
    EXPECT_EQ(r.arm, plan.arm[k]) << "sequence " << k;
    ASSERT_EQ(r.hand.size(), 22u);
    for (int h = 0; h < 22; ++h) EXPECT_EQ(r.hand[h], plan.hand[k][h]) << "sequence " << k;
    EXPECT_EQ(r.plan_time, plan.times[k]);
  }
}

// `deploy stream` of <dir>/plan.json on `channel` while lcm-logger records
// it into <dir>/run.lcmlog (its output in <dir>/logger.txt).
testing::CommandResult StreamUnderLcmLogger(const TempDir& dir, const std::string& url,
                                             const std::string& channel) {
  const pid_t logger = Spawn({"lcm-logger", "-f", "--lcm-url=" + url, "--channel=" + channel,
                              (dir / "run.lcmlog").string()}, dir / "logger.txt");
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  const auto r = RunDoasido({"deploy", "stream", "--plan", (dir / "plan.json").string(), "--url", url,
                             "--channel", channel});
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  kill(logger, SIGINT);
  WaitFor(logger);
  return r;
}

TEST(DeployStream, LcmLoggerRecordsFiftyHertz) {
  TempDir dir;
  const deploy::Plan plan = TenSecondPlan(true);
  deploy::WritePlanJson(plan, dir / "plan.json");
  const std::string url = LoopbackLcmUrl(), channel = "DOASIDO_TEST_" + std::to_string(getpid());
  const auto r = StreamUnderLcmLogger(dir, url, channel);
  ASSERT_EQ(r.exit_code, 0) << r.err << testing::ReadFile(dir / "logger.txt");
  EXPECT_NE(r.out.find("sent 500 of 500"), std::string::npos) << r.out;

  const auto got = deploy::ReadCommandLog(dir / "run.lcmlog", channel);
  ASSERT_GE(got.size(), 2u) << testing::ReadFile(dir / "logger.txt");
  const double mean_interval_ms =
      (got.back().log_time_us - got.front().log_time_us) / 1000.0 / (got.size() - 1);
  const double sender_interval_ms =
      (got.back().timestamp_us - got.front().timestamp_us) / 1000.0 / (got.size() - 1);
  std::printf("lcm-logger: %zu messages, mean interval %.4f ms (sender %.4f ms)\n", got.size(),
              mean_interval_ms, sender_interval_ms);
  EXPECT_NEAR(static_cast<double>(got.size()), 500.0, 2.0);
  EXPECT_NEAR(mean_interval_ms, 20.0, 0.4);
  ExpectEqualsPlan(got, plan);
  for (size_t i = 1; i < got.size(); ++i) EXPECT_GT(got[i].sequence, got[i - 1].sequence);
}

// A re-timed plan (the base joint asked for twice its speed limit, so the
// commands hold a slowed time map) is still sent one message per command,
// 20 ms apart, as lcm-logger's own receive times show.
TEST(DeployStream, RetimedPlanRecordedByLcmLoggerAtFiftyHertz) {
  TempDir dir;
  const double speed = 2 * deploy::Ur3eLimits().max_speed[0];
  const auto path = [&](double t) {
    deploy::ArmQ q(0.3, -1.9, 1.7, -1.4, -1.5, 0.2);
    q[0] += speed * (t - 0.75);
    return q;
  };
  const deploy::Plan plan = testing::PlanInBaseFrame(testing::FromJointPath(path, 76, 50), path(0));
  ASSERT_TRUE(plan.ok);
  ASSERT_GE(plan.slowdown, 2.0);
  deploy::WritePlanJson(plan, dir / "plan.json");
  const std::string url = LoopbackLcmUrl(), channel = "DOASIDO_RETIMED_" + std::to_string(getpid());
  const auto r = StreamUnderLcmLogger(dir, url, channel);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto got = deploy::ReadCommandLog(dir / "run.lcmlog", channel);
  ASSERT_EQ(got.size(), plan.arm.size()) << testing::ReadFile(dir / "logger.txt");
  std::vector<double> intervals;
  for (size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].sequence, static_cast<int64_t>(k));
    EXPECT_EQ(got[k].arm, plan.arm[k]);
    if (k) intervals.push_back((got[k].log_time_us - got[k - 1].log_time_us) / 1000.0);
  }
  const double mean = (got.back().log_time_us - got.front().log_time_us) / 1000.0 / intervals.size();
  std::vector<double> sorted = intervals;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  int within = 0;
  for (double i : intervals) within += std::abs(i - 20.0) <= 0.4;
  std::printf("re-timed plan (slowdown %.2f): %zu commands, lcm-logger mean interval %.4f ms, median %.4f ms, "
              "%d of %zu within 20 ms +- 2%%\n", plan.slowdown, got.size(), mean, median, within, intervals.size());
  EXPECT_NEAR(mean, 20.0, 0.4);
  EXPECT_NEAR(median, 20.0, 0.4);
}

TEST(DeployStream, DryRunLogHoldsThePlan) {
  TempDir dir;
  const deploy::Plan plan = TenSecondPlan(true);
  deploy::WritePlanJson(plan, dir / "plan.json");
  const auto r = RunDoasido({"deploy", "stream", "--plan", (dir / "plan.json").string(), "--dry-run",
                             (dir / "dry.lcmlog").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto got = deploy::ReadCommandLog(dir / "dry.lcmlog");
  ASSERT_EQ(got.size(), 500u);
  ExpectEqualsPlan(got, plan);
  EXPECT_EQ(got[499].log_time_us - got[0].log_time_us, 499 * 20000);
}

TEST(DeployStream, RefusesPlanThatFailedItsChecks) {
  TempDir dir;
  deploy::WritePlanJson(TenSecondPlan(false), dir / "plan.json");
  const auto r = RunDoasido({"deploy", "stream", "--plan", (dir / "plan.json").string(), "--dry-run",
                             (dir / "dry.lcmlog").string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("plan_failed_checks"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "dry.lcmlog"));
}

TEST(DeployStream, StopsCleanlyOnSigint) {
  TempDir dir;
  deploy::WritePlanJson(TenSecondPlan(true), dir / "plan.json");
  const pid_t pid = Spawn({testing::DoasidoBin().string(), "deploy", "stream", "--plan",
                           (dir / "plan.json").string(), "--url", LoopbackLcmUrl(), "--channel",
                           "DOASIDO_SIGINT_" + std::to_string(getpid())}, dir / "out.txt");
  // Once it says it streams (its Ctrl-C handler is in place), and a little later.
  for (int i = 0; i < 600 && testing::ReadFile(dir / "out.txt").find("streaming") == std::string::npos;
       ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  kill(pid, SIGINT);
  const int code = WaitFor(pid);
  const std::string out = testing::ReadFile(dir / "out.txt");
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("stopped after"), std::string::npos) << out;
}

// A floating-wrist trajectory at 10 fps whose wrist points down 0.25 m
// above the origin, `lift(k)` metres higher at frame k.
Json WristTrajectory(int frames, const std::function<double(int)>& lift) {
  Json t;
  t["embodiment"] = "sharpa_right";
  t["fps"] = 10;
  t["scale"] = 1;
  t["qpos_names"] = {"doasido_wrist_x", "doasido_wrist_y", "doasido_wrist_z",
                     "doasido_wrist_rx", "doasido_wrist_ry", "doasido_wrist_rz"};
  for (int k = 0; k < frames; ++k) {
    t["qpos"].push_back({0.0, 0.0, 0.25 + lift(k), M_PI, 0.0, 0.0});
    t["valid"].push_back(true);
    t["fingertip_error"].push_back(0.0);
  }
  t["object_poses"] = Json::array();
  return t;
}

TEST(DeployPlan, ReportsUnreachableFramesWithTimes) {
  TempDir dir;
  // A wrist that holds still for 1 s, then jumps 3 m up for 0.5 s.
  const Json t = WristTrajectory(20, [](int k) { return k >= 10 && k < 15 ? 3.0 : 0.0; });
  testing::WriteFile(dir / "trajectory.json", t.dump());
  const auto r = RunDoasido({"deploy", "plan", "--trajectory", (dir / "trajectory.json").string(),
                             "--out", (dir / "plan.json").string(), "--rate", "10",
                             "--yaw-steps", "1", "--offset-steps", "1", "--no-replay"});
  EXPECT_NE(r.exit_code, 0) << r.out << r.err;
  const deploy::Plan plan = deploy::ReadPlanJson(dir / "plan.json");
  EXPECT_FALSE(plan.ok);
  std::vector<double> times;
  for (const auto& u : plan.unreachable) times.push_back(u.time);
  EXPECT_EQ(times, (std::vector<double>{1.0, 1.1, 1.2, 1.3, 1.4})) << r.out;
  EXPECT_NE(r.out.find("unreachable  frame    10  t=  1.000 s"), std::string::npos) << r.out;
}

TEST(DeployPlan, TheConfigFilesDeploySectionIsReadAndChecked) {
  TempDir dir;
  // A wrist that holds still for 1 s.
  testing::WriteFile(dir / "trajectory.json", WristTrajectory(10, [](int) { return 0.0; }).dump());
  const auto plan_with = [&](const std::string& toml) {
    testing::WriteFile(dir / "deploy.toml", toml);
    return RunDoasido({"deploy", "plan", "--trajectory", (dir / "trajectory.json").string(),
                       "--out", (dir / "plan.json").string(), "--force", "--config",
                       (dir / "deploy.toml").string(), "--yaw-steps", "1", "--offset-steps",
                       "1", "--no-replay"});
  };
  // [deploy] and its tables reach the plan: the rate and the path check's
  // tolerance it records.
  auto r = plan_with("[deploy]\nrate_hz = 25\n[deploy.path_check]\nposition_tolerance = 0.02\n");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const deploy::Plan plan = deploy::ReadPlanJson(dir / "plan.json");
  EXPECT_DOUBLE_EQ(plan.rate_hz, 25);
  EXPECT_TRUE(plan.path_deviation.checked);
  EXPECT_DOUBLE_EQ(plan.path_deviation.position_tolerance, 0.02);
  // A value out of range and an unknown key are refused, naming them.
  r = plan_with("[deploy.path_check]\nposition_tolerance = -1\n");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("position_tolerance"), std::string::npos) << r.err;
  r = plan_with("[deploy]\nrate = 25\n");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("rate"), std::string::npos) << r.err;
}

// Two hands: `deploy plan-two` places two arms, `deploy stream` sends one
// bimanual_command per tick (dry run here; the live stream is recorded by
// lcm-logger in deploy_bimanual_test); bases 5 cm apart are refused with
// the colliding frames' times.
TEST(DeployPlanTwo, PlansTwoArmsAndStreamsThemAsOne) {
  TempDir dir;
  const testing::TwoHands& h = testing::TwoHandEpisode();
  retarget::WriteTrajectoryJson(h.left, dir / "left.json");
  retarget::WriteTrajectoryJson(h.right, dir / "right.json");
  const std::vector<std::string> plan_two = {"deploy", "plan-two", "--left", (dir / "left.json").string(),
                                             "--right", (dir / "right.json").string(), "--robots-dir",
                                             (testing::SharedData() / "robots").string()};
  std::vector<std::string> args = plan_two;
  args.insert(args.end(), {"--out", (dir / "two.json").string()});
  const auto ok = RunDoasido(args);
  ASSERT_EQ(ok.exit_code, 0) << ok.out << ok.err;
  EXPECT_NE(ok.out.find("sharpa_left + sharpa_right: bases 0.600 m apart"), std::string::npos) << ok.out;
  EXPECT_NE(ok.out.find("ok: 0 collision frames"), std::string::npos) << ok.out;
  const auto planned = deploy::BimanualPlanFromJson(deploy::ReadPlanFile(dir / "two.json"), "two");
  const size_t n = planned.right.arm.size();
  // One clock: both arms hold the same trajectory time at every command.
  EXPECT_EQ(planned.left.source_times, planned.right.source_times);
  EXPECT_NE(ok.out.find("re-timed: "), std::string::npos) << ok.out;
  const auto stream = RunDoasido({"deploy", "stream", "--plan", (dir / "two.json").string(), "--dry-run",
                                  (dir / "two.lcmlog").string()});
  ASSERT_EQ(stream.exit_code, 0) << stream.err;
  const std::string count = std::to_string(n);
  EXPECT_NE(stream.out.find("sent " + count + " of " + count), std::string::npos) << stream.out;
  EXPECT_EQ(deploy::ReadBimanualLog(dir / "two.lcmlog").size(), n);

  // The retarget stage's two-hand trajectory.json plans the same.
  retarget::WriteTrajectoryJson(retarget::CombineBimanualTrajectories(h.left, h.right), dir / "both.json");
  const auto one_file = RunDoasido({"deploy", "plan-two", "--trajectory", (dir / "both.json").string(),
                                    "--robots-dir", (testing::SharedData() / "robots").string(), "--out",
                                    (dir / "both_plan.json").string()});
  ASSERT_EQ(one_file.exit_code, 0) << one_file.out << one_file.err;
  const auto from_one = deploy::BimanualPlanFromJson(deploy::ReadPlanFile(dir / "both_plan.json"), "both");
  const auto from_two = deploy::BimanualPlanFromJson(deploy::ReadPlanFile(dir / "two.json"), "two");
  EXPECT_EQ(from_one.left.arm, from_two.left.arm);
  EXPECT_EQ(from_one.right.arm, from_two.right.arm);

  // `deploy plan` (one arm) names the command for it.
  const auto one_arm = RunDoasido({"deploy", "plan", "--trajectory", (dir / "both.json").string(), "--out",
                                   (dir / "one.json").string()});
  EXPECT_EQ(one_arm.exit_code, 1) << one_arm.err;
  EXPECT_NE(one_arm.err.find("two_hand_trajectory"), std::string::npos) << one_arm.err;
  EXPECT_NE(one_arm.err.find("deploy plan-two --trajectory " + (dir / "both.json").string()), std::string::npos)
      << one_arm.err;

  args = plan_two;
  args.insert(args.end(), {"--out", (dir / "close.json").string(), "--base-distance", "0.05"});
  const auto close = RunDoasido(args);
  EXPECT_NE(close.exit_code, 0);
  EXPECT_NE(close.out.find("collision    command     0  t=  0.000 s"), std::string::npos) << close.out;
  EXPECT_NE(close.err.find("plan_failed_checks"), std::string::npos) << close.err;
  const auto refused = RunDoasido({"deploy", "stream", "--plan", (dir / "close.json").string(), "--dry-run",
                                   (dir / "close.lcmlog").string()});
  EXPECT_NE(refused.exit_code, 0);
  const auto close_plan = deploy::BimanualPlanFromJson(deploy::ReadPlanFile(dir / "close.json"), "close");
  EXPECT_NE(refused.err.find(std::to_string(close_plan.right.arm.size()) +
                             " arm-arm collision commands (0.000000 s, 0.020000 s"),
            std::string::npos) << refused.err;
}

}  // namespace
}  // namespace doasido
