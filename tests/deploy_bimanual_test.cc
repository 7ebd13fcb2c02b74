// Two arms (deploy/bimanual.h) on a synthetic two-hand episode (synth
// module: the right hand picks the object, the left one hovers beside it),
// each hand retargeted onto its side's robot hand: bases 60 cm apart plan
// without an arm-arm collision; bases 5 cm apart overlap in every frame and
// the stream refuses the plan naming the frames' times; Debian's
// lcm-logger (an independent process) records both arms' commands at 50 Hz;
// a two-hand carry replayed with both arms in one scene reports each arm's
// wrist tracking and the object, as the two floating hands' replay does.
#include <sys/resource.h>

#include <chrono>
#include <ctime>
#include <optional>
#include <csignal>
#include <thread>

#include <gtest/gtest.h>

#include "core/error.h"
#include "deploy/bimanual.h"
#include "retarget/scene/scene_builder.h"
#include "robot/trajectory/format.h"
#include "tests/test_util.h"
#include "tests/two_hand_episode.h"

namespace doasido::deploy {
namespace {

using doasido::testing::TempDir;

using doasido::testing::TwoHandEpisode;
using doasido::testing::TwoHands;

TEST(Bimanual, ArmsSixtyCentimetresApartDoNotCollide) {
  const TwoHands& h = TwoHandEpisode();
  BimanualConfig config;
  const BimanualPlan plan = MakeBimanualPlan(h.left, h.right, h.left_hand, h.right_hand, config);
  ASSERT_EQ(plan.arm_distance.size(), plan.right.arm.size());
  const double closest = *std::min_element(plan.arm_distance.begin(), plan.arm_distance.end());
  for (const auto& f : plan.right.too_fast) std::printf("too fast right k %d t %.2f joint %d %.2f > %.2f\n", f.frame, f.time, f.joint, f.value, f.limit);
  for (const auto& f : plan.left.too_fast) std::printf("too fast left k %d t %.2f joint %d %.2f > %.2f\n", f.frame, f.time, f.joint, f.value, f.limit);
  std::printf("two-arm plan: %zu commands, closest approach of the arms %.3f m; unreachable left %zu right %zu\n",
              plan.right.arm.size(), closest, plan.left.unreachable.size(), plan.right.unreachable.size());
  EXPECT_TRUE(plan.collisions.empty());
  EXPECT_GT(closest, config.clearance);
  EXPECT_TRUE(plan.left.ok);
  EXPECT_TRUE(plan.right.ok);
  EXPECT_TRUE(plan.ok);
  // Both arms stay on their wrists' paths between frames (a clean
  // episode: the joint spline against the interpolated wrist, a few mm).
  for (const Plan* side : {&plan.left, &plan.right}) {
    EXPECT_TRUE(side->path_deviation.checked);
    EXPECT_TRUE(side->path_deviation.off_path.empty());
    EXPECT_LT(side->path_deviation.position_max, 0.005);
  }
  std::printf("between frames: left %.2f mm, right %.2f mm\n", 1000 * plan.left.path_deviation.position_max,
              1000 * plan.right.path_deviation.position_max);
  // The bases are where the config puts them: base_distance apart, level.
  const Vec3 left_base = plan.left.placement.world_to_base.Inverse().t;
  const Vec3 right_base = plan.right.placement.world_to_base.Inverse().t;
  EXPECT_NEAR((left_base - right_base).norm(), 0.6, 1e-12);
  EXPECT_NEAR(left_base.z(), right_base.z(), 1e-12);
}

// Bases 5 cm apart: the two base links (radius 4.5 cm, vertical from the
// base) overlap by 4 cm whatever the joints do, so every frame collides.
TEST(Bimanual, ArmsPlacedTooCloseAreRefusedWithTheFrameTimes) {
  const TwoHands& h = TwoHandEpisode();
  BimanualConfig config;
  config.base_distance = 0.05;
  const BimanualPlan plan = MakeBimanualPlan(h.left, h.right, h.left_hand, h.right_hand, config);
  ASSERT_EQ(plan.collisions.size(), plan.right.arm.size());
  for (const FrameIssue& c : plan.collisions) {
    EXPECT_LE(c.value, 0.05 - 2 * 0.045 + 1e-9);
    EXPECT_DOUBLE_EQ(c.time, plan.right.times[c.frame]);
  }
  EXPECT_FALSE(plan.ok);
  try {
    std::atomic<bool> stop{false};
    StreamBimanualPlan(plan, {.dry_run_log = "/nonexistent/never.lcmlog"}, stop);
    ADD_FAILURE() << "a colliding plan was streamed";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "plan_failed_checks");
    const std::string what = e.what();
    for (int k = 0; k < 3; ++k) {
      EXPECT_NE(what.find(std::to_string(plan.right.times[k]) + " s"), std::string::npos) << what;
    }
  }
}

void ExpectEqualsPlan(const BimanualRecord& r, const BimanualPlan& plan) {
  ASSERT_GE(r.sequence, 0);
  ASSERT_LT(r.sequence, static_cast<int64_t>(plan.right.arm.size()));
  const size_t k = static_cast<size_t>(r.sequence);
  EXPECT_EQ(r.left_arm, plan.left.arm[k]);
  EXPECT_EQ(r.right_arm, plan.right.arm[k]);
  const Eigen::VectorXd& l = plan.left.hand[k];
  const Eigen::VectorXd& rh = plan.right.hand[k];
  EXPECT_EQ(r.left_hand, std::vector<double>(l.data(), l.data() + l.size()));
  EXPECT_EQ(r.right_hand, std::vector<double>(rh.data(), rh.data() + rh.size()));
  EXPECT_EQ(r.plan_time, plan.right.times[k]);
}

TEST(Bimanual, LcmLoggerRecordsBothArmsAtFiftyHertz) {
  TempDir dir;
  const TwoHands& h = TwoHandEpisode();
  const BimanualPlan plan = MakeBimanualPlan(h.left, h.right, h.left_hand, h.right_hand, {});
  ASSERT_TRUE(plan.ok);
  const std::string url = testing::LoopbackLcmUrl(), channel = "DOASIDO_BIMANUAL_" + std::to_string(getpid());
  const int logger = testing::Spawn(
      {"lcm-logger", "-f", "--lcm-url=" + url, "--channel=" + channel, (dir / "run.lcmlog").string()},
      dir / "logger.txt");
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  std::atomic<bool> stop{false};
  const StreamResult sent = StreamBimanualPlan(plan, {.url = url, .channel = channel}, stop);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  kill(logger, SIGINT);
  testing::WaitFor(logger);
  EXPECT_EQ(sent.sent, static_cast<int>(plan.right.arm.size()));

  const std::vector<BimanualRecord> got = ReadBimanualLog(dir / "run.lcmlog", channel);
  ASSERT_GE(got.size(), 2u) << testing::ReadFile(dir / "logger.txt");
  const double interval_ms = (got.back().log_time_us - got.front().log_time_us) / 1000.0 / (got.size() - 1);
  std::printf("lcm-logger: %zu two-arm commands of %zu, mean interval %.4f ms\n", got.size(),
              plan.right.arm.size(), interval_ms);
  EXPECT_NEAR(static_cast<double>(got.size()), static_cast<double>(plan.right.arm.size()), 1.0);
  EXPECT_NEAR(interval_ms, 20.0, 0.4);
  for (const BimanualRecord& r : got) ExpectEqualsPlan(r, plan);
  for (size_t i = 1; i < got.size(); ++i) EXPECT_GT(got[i].sequence, got[i - 1].sequence);

  // The dry run writes the same messages at the planned times.
  StreamBimanualPlan(plan, {.dry_run_log = dir / "dry.lcmlog"}, stop);
  const std::vector<BimanualRecord> dry = ReadBimanualLog(dir / "dry.lcmlog");
  ASSERT_EQ(dry.size(), plan.right.arm.size());
  for (const BimanualRecord& r : dry) ExpectEqualsPlan(r, plan);
  EXPECT_EQ(dry.back().log_time_us - dry.front().log_time_us,
            static_cast<int64_t>(dry.size() - 1) * 20000);
}

// A 2-s two-hand carry of a cylinder (synth), each hand retargeted
// kinematically with the grasp terms onto its Sharpa hand in the object's
// scene, combined into one two-hand trajectory whose object poses are the
// episode's own.
struct Carry {
  retarget::Embodiment left_hand, right_hand;
  retarget::HandTrajectory both;
  std::string scene_xml;
};

Carry MakeCarry(const std::filesystem::path& dir) {
  synth::EpisodeSpec spec;
  spec.frames = 60;
  spec.two_hand_task = synth::TwoHandTask::kCarry;
  spec.grasp = synth::GraspTypeFromName("pinch");
  const TriMesh mesh = synth::MakeCylinder(0.035, 0.10, 16);
  const recon::Reconstruction r = synth::EpisodeReconstruction(synth::ScriptEpisode(spec, mesh), 30.0);
  retarget::SceneConfig scene_config;
  scene_config.place_on_floor = false;
  const retarget::ObjectScene scene = retarget::BuildObjectScene(mesh, r.object_poses[0], scene_config, dir);
  Carry c{.left_hand = retarget::FindEmbodiment("sharpa_left", testing::SharedData() / "robots"),
          .right_hand = retarget::FindEmbodiment("sharpa_right", testing::SharedData() / "robots"),
          .scene_xml = testing::ReadFile(scene.xml_path)};
  retarget::KinematicConfig config;
  config.restarts = 1;
  const auto solve = [&](const retarget::Embodiment& e, const std::vector<recon::Joints21>& joints,
                         const std::vector<bool>& valid) {
    const retarget::HandModel model = retarget::BuildHandModel(e, c.scene_xml, dir);  // outlives the solver
    retarget::KinematicRetargeter k(model, config);
    return k.Solve(joints, valid, r.fps, {}, &r.object_poses);
  };
  c.both = retarget::CombineBimanualTrajectories(solve(c.left_hand, r.left_joints, r.left_valid),
                                                 solve(c.right_hand, r.right_joints, r.right_valid));
  c.both.object_poses = r.object_poses;
  return c;
}

void ExpectReportsEveryCommand(const BimanualPlan& plan, const char* what) {
  const size_t path = plan.right.arm.size() - plan.right.lead_in - plan.right.lead_out;
  for (const Plan* side : {&plan.left, &plan.right}) {
    const ReplayReport& r = side->replay;
    ASSERT_TRUE(r.ran) << what;
    EXPECT_EQ(r.wrist_position_error.size(), path) << what;
    EXPECT_EQ(r.finger_error.size(), path) << what;
    EXPECT_EQ(r.hand_contacts.size(), path) << what;
    EXPECT_EQ(r.object_position_error.size(), path) << what;
  }
  // One object for both arms.
  EXPECT_EQ(plan.left.replay.object_position_error, plan.right.replay.object_position_error) << what;
}

TEST(Bimanual, BothArmsReplayACarryInOneSceneWithTheObject) {
  TempDir dir;
  const Carry c = MakeCarry(dir.path());
  const auto [left, right] = retarget::SplitBimanualTrajectory(c.both);
  BimanualPlan arms = MakeBimanualPlan(left, right, c.left_hand, c.right_hand, {});
  ASSERT_TRUE(arms.ok);
  BimanualPlan floating = arms;
  ReplayBimanualPlan(arms, c.both, c.left_hand, c.right_hand, c.scene_xml, dir.path());
  ReplayBimanualPlan(floating, c.both, c.left_hand, c.right_hand, c.scene_xml, dir.path(), PlanConfig{}.servo_omega,
                     ReplayMount::kFloating);
  ExpectReportsEveryCommand(arms, "arms");
  ExpectReportsEveryCommand(floating, "floating");
  for (const BimanualPlan* p : {&arms, &floating}) {
    std::printf("%s: object %.1f mm / %.3f rad (max %.1f mm), wrist left %.2f / %.2f mm, right %.2f / %.2f mm, "
                "contacts left %d right %d\n", p == &arms ? "arms" : "floating",
                1000 * p->right.replay.object_position_error_mean, p->right.replay.object_rotation_error_mean,
                1000 * p->right.replay.object_position_error_max, 1000 * p->left.replay.wrist_position_error_mean,
                1000 * p->left.replay.wrist_position_error_max, 1000 * p->right.replay.wrist_position_error_mean,
                1000 * p->right.replay.wrist_position_error_max,
                *std::max_element(p->left.replay.hand_contacts.begin(), p->left.replay.hand_contacts.end()),
                *std::max_element(p->right.replay.hand_contacts.begin(), p->right.replay.hand_contacts.end()));
  }
  // Each arm's flange follows its own hand's wrist path (IK within 1 mm at
  // the frames, the servo between them) while its hand is free; in contact
  // the kinematic grasp's overlap with the object pushes it, as it pushes
  // the floating wrist, which yields more.
  for (const Plan* side : {&arms.left, &arms.right}) {
    const ReplayReport& r = side->replay;
    double free_sum = 0, free_max = 0;
    int free = 0;
    for (size_t k = 0; k < r.hand_contacts.size(); ++k) {
      if (r.hand_contacts[k] > 0) continue;
      free_sum += r.wrist_position_error[k];
      free_max = std::max(free_max, r.wrist_position_error[k]);
      ++free;
    }
    ASSERT_GT(free, 10);
    EXPECT_LT(free_sum / free, 0.003);
    EXPECT_LT(free_max, 0.010);
  }
  EXPECT_LT(arms.left.replay.wrist_position_error_mean, floating.left.replay.wrist_position_error_mean);
  EXPECT_LT(arms.right.replay.wrist_position_error_mean, floating.right.replay.wrist_position_error_mean);
  // The arms do to the object what the floating hands do under the same time map.
  EXPECT_NEAR(arms.right.replay.object_position_error_mean, floating.right.replay.object_position_error_mean, 0.01);
  EXPECT_EQ(arms.right.replay.success, floating.right.replay.success);

  // Written into the two-arm plan file and read back.
  WriteBimanualPlanJson(arms, {}, dir / "two.json");
  const BimanualPlan back = BimanualPlanFromJson(ReadPlanFile(dir / "two.json"), "two.json");
  EXPECT_EQ(back.left.replay.wrist_position_error, arms.left.replay.wrist_position_error);
  EXPECT_EQ(back.right.replay.hand_contacts, arms.right.replay.hand_contacts);
  EXPECT_EQ(back.right.replay.success, arms.right.replay.success);
}

// MakeBimanualPlan under a 4 GiB address-space cap (an unbounded
// re-timing throws bad_alloc instead of filling the machine), its CPU time.
struct CappedRun {
  std::optional<BimanualPlan> plan;
  std::string code, what;
  double cpu_seconds = 0;
};
CappedRun PlanCapped(const TwoHands& h, const BimanualConfig& config) {
  rlimit before{};
  getrlimit(RLIMIT_AS, &before);
  rlimit capped = before;
  capped.rlim_cur = 4ull << 30;
  if (before.rlim_cur == RLIM_INFINITY || before.rlim_cur > capped.rlim_cur) setrlimit(RLIMIT_AS, &capped);
  CappedRun run;
  const std::clock_t cpu0 = std::clock();
  try {
    run.plan = MakeBimanualPlan(h.left, h.right, h.left_hand, h.right_hand, config);
  } catch (const Error& e) {
    run.code = e.code();
    run.what = e.what();
  } catch (const std::bad_alloc&) {
    run.code = "bad_alloc";
  }
  run.cpu_seconds = double(std::clock() - cpu0) / CLOCKS_PER_SEC;
  setrlimit(RLIMIT_AS, &before);
  return run;
}

// The pair placed with its frame on the bases' line (workspace x = 0): the
// hands' wrists between and around the bases, many frames out of either
// arm's reach. The IK used to keep a random start's least-bad answer
// there, the joint path jumped from frame to frame, and re-timing it ran
// out of memory (tens of GB of commands). Now the path stays continuous
// through the frames out of reach (their warm starts kept) and the plan
// is made, failing its reach check; and a path the re-timing cannot
// follow within max_slowdown (here made so by a bound of 1.2x) stops at
// the bound, naming the arm, its frames and the placement.
TEST(Bimanual, APairPlacedOutOfReachFailsFastNamingTheArmTheFramesAndThePlacement) {
  const TwoHands& h = TwoHandEpisode();
  BimanualConfig config;
  config.plan.workspace.x = 0;
  config.plan.workspace.offset_steps = 1;  // this spot only
  const CappedRun planned = PlanCapped(h, config);
  ASSERT_TRUE(planned.plan) << planned.code << " " << planned.what;
  const BimanualPlan& plan = *planned.plan;
  std::printf("x = 0: %.1f CPU s, unreachable left %zu right %zu, slowdown %.2fx\n", planned.cpu_seconds,
              plan.left.unreachable.size(), plan.right.unreachable.size(), plan.right.slowdown);
  EXPECT_LT(planned.cpu_seconds, 30);
  EXPECT_FALSE(plan.ok);
  EXPECT_GT(plan.left.unreachable.size() + plan.right.unreachable.size(), 0u);
  EXPECT_LE(plan.right.slowdown, config.plan.time_scaling.max_slowdown);

  config.plan.time_scaling.max_slowdown = 1.2;
  const CappedRun bounded = PlanCapped(h, config);
  std::printf("bounded at 1.2x: %.1f CPU s: %s\n", bounded.cpu_seconds, bounded.what.c_str());
  EXPECT_EQ(bounded.code, kUnfollowablePath);
  EXPECT_LT(bounded.cpu_seconds, 30);
  const std::string& what = bounded.what;
  EXPECT_TRUE(what.find("sharpa_left arm") != std::string::npos || what.find("sharpa_right arm") != std::string::npos)
      << what;
  EXPECT_NE(what.find("between frames"), std::string::npos) << what;
  EXPECT_NE(what.find("frames out of reach"), std::string::npos) << what;
  EXPECT_NE(what.find("placement x 0.000 m, y 0.000 m"), std::string::npos) << what;
}

}  // namespace
}  // namespace doasido::deploy
