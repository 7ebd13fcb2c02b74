// Dynamics-aware retargeting (annealed sampling, seed section 3.2): the
// sampler's pieces against hand-computed values, the metrics against their
// published definition, determinism, the named errors, and the `retarget`
// stage on a synthetic reconstruction (scripted pick-and-place episode of
// the synth module, a cylinder on the floor).
#include <cmath>
#include <fstream>
#include <functional>

#include <gtest/gtest.h>

#include "eval/reconstruction_noise.h"
#include "retarget/dynamic/annealed_sampler.h"
#include "retarget/dynamic/dynamic_reference.h"
#include "retarget/dynamic/dynamic_retarget.h"
#include "retarget/dynamic/retarget_reward.h"
#include "retarget/dynamic/sampler_ladder.h"
#include "stages/dynamic_stage.h"
#include "stages/kinematic_stage.h"
#include "synth/objects.h"
#include "tests/small_retarget_config.h"
#include "tests/test_util.h"

namespace doasido::retarget {
namespace {

using doasido::testing::SharedData;
using doasido::testing::ErrorCode;
using doasido::testing::TempDir;

constexpr int kFrames = 20;
constexpr int kLadderFrames = 60;

TriMesh Cylinder() { return synth::MakeCylinder(0.03, 0.08, 16); }

recon::Reconstruction Reference(int frames = kFrames, synth::Verb verb = synth::Verb::kPickPlace) {
  synth::EpisodeSpec spec;
  spec.frames = frames;
  spec.verb = verb;
  return synth::EpisodeReconstruction(synth::ScriptEpisode(spec, Cylinder()), 30.0);
}

DynamicRetargetConfig SmallConfig(int threads = 2) { return testing::SmallRetargetConfig(threads); }

DynamicRetargetRun Retarget(const recon::Reconstruction& r, const DynamicRetargetConfig& c,
                       const TempDir& dir) {
  return RetargetReconstruction(r, Cylinder(), FindEmbodiment(c.hand, c.robots_dir), c,
                                dir / "scene", "synthetic");
}

TEST(KnotSpline, InterpolatesLinearlyAndHoldsTheLastKnot) {
  const double knots[] = {0, 10, 1, 20, 3, 40};  // 3 knots, 2 dims
  double out[2];
  EXPECT_EQ(KnotCount(1.0, 0.25), 5);
  EXPECT_EQ(KnotCount(3.0, 0.2), 16);
  EvaluateKnots(knots, 3, 2, 0.2, 0.05, out);
  EXPECT_NEAR(out[0], 0.25, 1e-12);
  EXPECT_NEAR(out[1], 12.5, 1e-12);
  EvaluateKnots(knots, 3, 2, 0.2, 0.3, out);
  EXPECT_NEAR(out[0], 2.0, 1e-12);
  EXPECT_NEAR(out[1], 30.0, 1e-12);
  EvaluateKnots(knots, 3, 2, 0.2, 7.0, out);
  EXPECT_EQ(out[0], 3.0);
  EXPECT_EQ(out[1], 40.0);
}

TEST(AnnealedSampler, NoiseGrowsAlongTheHorizonBySeedScales) {
  const AnnealedSamplerConfig c;  // seed table
  const RowMatrix sigma = NoiseScales(c, {kBasePos, kBaseRot, kFinger}, 16);
  EXPECT_NEAR(sigma(0, 0), 0.01, 1e-12);
  EXPECT_NEAR(sigma(0, 1), 0.01, 1e-12);
  EXPECT_NEAR(sigma(0, 2), 0.1, 1e-12);
  EXPECT_NEAR(sigma(15, 2), 0.4, 1e-12);
  EXPECT_NEAR(sigma(8, 2) / sigma(7, 2), std::pow(4.0, 1.0 / 15), 1e-12);
}

TEST(AnnealedSampler, SampleZeroIsNoiseFreeAndOthersHaveTheAnnealedSpread) {
  RowMatrix nominal(4, 2), sigma = RowMatrix::Constant(4, 2, 0.1);
  nominal << 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8;
  const std::vector<double> lo(2, -10), hi(2, 10);
  std::vector<double> out;
  const int samples = 2000;
  DrawSamples(nominal, sigma, 0.5, 11, lo, hi, samples, out);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(out[i], nominal.data()[i]);
  double sum2 = 0;
  for (int c = 1; c < samples; ++c) {
    for (int i = 0; i < 8; ++i) sum2 += std::pow(out[c * 8 + i] - nominal.data()[i], 2);
  }
  EXPECT_NEAR(std::sqrt(sum2 / ((samples - 1) * 8)), 0.05, 0.002);
  std::vector<double> again;
  DrawSamples(nominal, sigma, 0.5, 11, lo, hi, samples, again);
  EXPECT_EQ(out, again);
  const std::vector<double> tight_lo(2, 0.3), tight_hi(2, 0.5);
  DrawSamples(nominal, sigma, 1.0, 12, tight_lo, tight_hi, 50, out);
  for (double v : out) EXPECT_TRUE(v >= 0.3 && v <= 0.5);
}

TEST(AnnealedSampler, WeightsAreASoftmaxOfZScoredTopReturns) {
  const std::vector<double> returns = {1, 2, 3, 4, 5, 6, 7, 8, 10, 9};
  std::vector<double> w;
  WeightSamples(returns, 0.2, 1.0, w);  // top 2: {10, 9}, mean 9.5, sd 0.5, z = +-1
  const double e = std::exp(2.0);
  EXPECT_NEAR(w[8], e / (e + 1), 1e-9);
  EXPECT_NEAR(w[9], 1 / (e + 1), 1e-9);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(w[i], 0.0);
  WeightSamples(returns, 0.2, 0.1, w);  // temperature 0.1: z / 0.1 = +-10
  EXPECT_NEAR(w[8], 1 / (1 + std::exp(-20.0)), 1e-12);
}

TEST(AnnealedSampler, PresetsAndRangeChecks) {
  EXPECT_EQ(SamplerPreset("seed").num_samples, 1024);
  EXPECT_EQ(SamplerPreset("seed").max_num_iterations, 32);
  EXPECT_EQ(SamplerPreset("fast").num_samples, 64);
  EXPECT_EQ(ErrorCode([] { SamplerPreset("turbo"); }), "bad_config");
  AnnealedSamplerConfig bad;
  bad.perturb_prob = 1.5;
  EXPECT_EQ(ErrorCode([&] { CheckConfig(bad, "retarget.sampler"); }), "bad_config");
  bad = {};
  bad.perturb_gate_seconds = -0.1;
  EXPECT_EQ(ErrorCode([&] { CheckConfig(bad, "retarget.sampler"); }), "bad_config");
  DynamicRetargetConfig c;
  c.sampler.reward.transition_epsilon = 0;
  EXPECT_EQ(ErrorCode([&] { stages::DynamicRetargetStage stage(c); }), "bad_config");
  c = {};
  c.sampler.reward.transition_rest_height = -0.01;
  EXPECT_EQ(ErrorCode([&] { stages::DynamicRetargetStage stage(c); }), "bad_config");
}

// The transition reward per hand on a two-hand scene of boxes: the left
// hand touches the object, the right one is 10 cm away. Hands are found by
// their wrist mounts (in body order) and every body under a mount is that
// hand's; a stage whose holding hands all touch costs nothing, one where a
// holding hand does not costs transition_penalty_scale; resting, the
// object's floor contact is what counts; neither, nothing is asked.
// A box on the floor between two one-joint "hands": the left one's finger
// just touches it, the right one stands apart.
ModelPtr TwoHandsAndABox() {
  const std::string mount = kWristMountBody;
  return CompileMjcfText(R"(<mujoco><worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="object" pos="0 0 0.05"><freejoint/><geom type="box" size="0.05 0.05 0.05"/></body>
    <body name="l_)" + mount + R"(" pos="-0.069 0 0.05"><joint name="lx" type="slide" axis="1 0 0"/>
      <body name="l_finger"><geom type="box" size="0.02 0.02 0.02"/></body></body>
    <body name="r_)" + mount + R"(" pos="0.17 0 0.05"><joint name="rx" type="slide" axis="1 0 0"/>
      <geom type="box" size="0.02 0.02 0.02"/></body>
  </worldbody><actuator><position joint="lx"/><position joint="rx"/></actuator></mujoco>)",
                         "two boxes");
}

TEST(RetargetReward, TheTransitionRewardAsksEachHoldingHandForContact) {
  const std::string mount = kWristMountBody;
  const ModelPtr model = TwoHandsAndABox();
  const mjModel* m = model.get();
  const SceneIndex index = IndexScene(m);
  ASSERT_EQ(index.hands, (std::vector<std::string>{"l_" + mount, "r_" + mount}));
  EXPECT_EQ(index.body_hand[NameToId(m, mjOBJ_BODY, "l_finger")], 0);
  EXPECT_EQ(index.body_hand[NameToId(m, mjOBJ_BODY, "object")], -1);
  DataPtr d = MakeData(m);
  mj_forward(m, d.get());
  DynamicReference ref;
  ref.ctrl = RowMatrix::Zero(1, m->nu);
  ref.object_pos = {Vec3(0, 0, 0.05)};
  ref.object_quat = {Quat::Identity()};
  RewardConfig config;
  config.penetration = false;
  auto reward = [&](uint8_t holding, bool resting, bool transition) {
    ref.in_hand = {holding};
    ref.resting = {resting};
    config.transition = transition;
    return StepReward(m, d.get(), index, ref, 0, config);
  };
  const double tracking = reward(0, false, false), penalty = config.transition_penalty_scale;
  EXPECT_DOUBLE_EQ(reward(0, true, true), tracking);             // resting on the floor
  EXPECT_DOUBLE_EQ(reward(0, false, true), tracking);            // in the air, no hand near: nothing asked
  EXPECT_DOUBLE_EQ(reward(0b01, false, true), tracking);         // the left hand holds and touches
  EXPECT_DOUBLE_EQ(reward(0b10, false, true), tracking - penalty);  // the right one holds, apart
  EXPECT_DOUBLE_EQ(reward(0b11, false, true), tracking - penalty);  // both hold, one apart
  // Lifted off the floor, the object that should rest costs the penalty.
  d->qpos[index.object_qpos + 2] += 0.02;
  mj_forward(m, d.get());
  EXPECT_DOUBLE_EQ(reward(0, true, true), reward(0, true, false) - penalty);
}

// The parts the trace prints (RewardTerms) are the reward taken apart:
// the tracking norm of their squares, minus both penalties.
TEST(RetargetReward, ItsPartsMakeTheReward) {
  const ModelPtr model = TwoHandsAndABox();
  const mjModel* m = model.get();
  const SceneIndex index = IndexScene(m);
  DataPtr d = MakeData(m);
  d->qpos[index.act_qpos[0]] = 0.012;  // the left finger 11 mm into the box
  mj_forward(m, d.get());
  DynamicReference ref;
  ref.ctrl = RowMatrix::Constant(1, m->nu, 0.004);
  ref.object_pos = {Vec3(0.03, 0, 0.05)};
  ref.object_quat = {Quat(Eigen::AngleAxisd(0.2, Vec3::UnitZ()))};
  ref.in_hand = {0b10};  // the right hand should hold it and stands apart
  ref.resting = {false};
  const RewardConfig config;
  RewardTerms terms;
  const double reward = StepReward(m, d.get(), index, ref, 0, config, &terms);
  EXPECT_DOUBLE_EQ(reward, StepReward(m, d.get(), index, ref, 0, config));
  EXPECT_NEAR(terms.object_pos_sq, 0.03 * 0.03, 1e-9);
  EXPECT_NEAR(terms.object_rot_sq, std::pow(config.rot_rew_scale * 0.2, 2), 1e-9);
  EXPECT_GT(terms.penetration_depth, 0.005);
  EXPECT_TRUE(terms.stage_missed);
  const double tracking = terms.object_pos_sq + terms.object_rot_sq + terms.wrist_pos_sq + terms.wrist_rot_sq +
                          terms.fingers_sq;
  EXPECT_GT(terms.wrist_pos_sq + terms.wrist_rot_sq + terms.fingers_sq, 0);
  EXPECT_NEAR(reward, -std::sqrt(tracking) - config.penetration_penalty_scale * terms.penetration_depth -
                          config.transition_penalty_scale, 1e-12);
}

TEST(DynamicReference, AnObjectOnTheFloorRestsOnlyWithNoHandNearAndIsInNoHand) {
  const TriMesh cylinder = Cylinder();  // radius 3 cm, height 8 cm, base at z = 0
  const Quat on_side(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()));
  const std::vector<Pose> object = {{Quat::Identity(), Vec3(0, 0, 0)},
                                    {Quat::Identity(), Vec3(0.1, 0, 0.02)},
                                    {on_side, Vec3(0, 0, 0.0305)},
                                    {on_side, Vec3(0, 0, 0.045)}};
  EXPECT_EQ(LabelResting(object, cylinder, 0.01), (std::vector<bool>{true, false, true, false}));

  const DynamicRetargetConfig c = SmallConfig();
  TempDir dir;
  const ObjectScene scene = BuildObjectScene(cylinder, object[0], c.scene, dir / "scene");
  std::ifstream in(scene.xml_path);
  const HandModel hand = BuildHandModel(FindEmbodiment(c.hand, c.robots_dir),
                                        std::string((std::istreambuf_iterator<char>(in)), {}), dir / "scene");
  KinematicRetargeter kinematic(hand, c.kinematic);
  const recon::Reconstruction r = Reference(4);
  const HandTrajectory t = kinematic.Solve(r.right_joints, r.right_valid, r.fps);
  const DynamicReference ref = BuildReference(hand.model.get(), t, object, {1, 1, 0, 1},
                                              LabelResting(object, cylinder, 0.01), 0.0);
  // Frame 0 lies on the floor with a hand near it (a grasp or a release):
  // no rest (seed stages: floor contact may end any step), nor in hand
  // (the perturbations' gate). A reference lifting the object through the
  // rest band otherwise costs a rollout that follows it the transition
  // penalty (issue 51).
  const std::vector<uint8_t> in_hand = {0, 1, 0, 1}, resting = {0, 0, 1, 0};
  for (int f = 0; f < 4; ++f) {
    const int s = ref.StepOfFrame(f);
    EXPECT_EQ(ref.in_hand[s], in_hand[f]) << "frame " << f;
    EXPECT_EQ(ref.resting[s], resting[f]) << "frame " << f;
  }
}

TEST(AnnealedSampler, PerturbationsOnlyWhereTheObjectIsHeldOffTheFloor) {
  DynamicReference ref;
  ref.dt = 0.005;
  ref.warmup_steps = 20;
  ref.ctrl = RowMatrix::Zero(400, 1);
  ref.in_hand.assign(400, 0);
  std::fill(ref.in_hand.begin() + 100, ref.in_hand.begin() + 300, 1);
  AnnealedSamplerConfig c;
  c.perturb_gate_seconds = 0.25;  // 50 steps
  const std::vector<uint8_t> gate = PerturbationGate(ref, c);
  for (int s = 0; s < 400; ++s) EXPECT_EQ(gate[s], s >= 150 && s < 250) << "step " << s;
  // Held from the first step: not before warmup and the lag have passed.
  std::fill(ref.in_hand.begin(), ref.in_hand.begin() + 100, 1);
  const std::vector<uint8_t> early = PerturbationGate(ref, c);
  EXPECT_EQ(std::find(early.begin(), early.end(), 1) - early.begin(), 70);
  c.perturb = false;
  const std::vector<uint8_t> off = PerturbationGate(ref, c);
  EXPECT_EQ(std::count(off.begin(), off.end(), 1), 0);
}

TEST(DynamicRetarget, OnlyAReferenceThatLiftsTheObjectIsPerturbed) {
  TempDir dir;
  DynamicRetargetConfig with = SmallConfig(), without = SmallConfig();
  without.sampler.perturb = false;
  const recon::Reconstruction slide = Reference(kFrames, synth::Verb::kSlide);
  const DynamicRetargetRun a = Retarget(slide, with, dir), b = Retarget(slide, without, dir);
  ASSERT_EQ(a.in_hand_frames, 0);  // the hand is near, but the object stays on the floor
  EXPECT_EQ(a.stats.rollouts, b.stats.rollouts);
  for (int f = 0; f < kFrames; ++f) EXPECT_EQ(a.trajectory.qpos[f], b.trajectory.qpos[f]) << "frame " << f;

  const recon::Reconstruction lift = Reference(kFrames, synth::Verb::kPickPlace);
  with.sampler.perturb_gate_seconds = 0.02;  // this short lift is held for 0.23 s
  with.sampler.perturb_prob = 1;
  const DynamicRetargetRun c = Retarget(lift, with, dir), d = Retarget(lift, without, dir);
  ASSERT_GT(c.in_hand_frames, 0);
  bool differs = false;
  for (int f = 0; f < kFrames; ++f) differs |= c.trajectory.ctrl[f] != d.trajectory.ctrl[f];
  EXPECT_TRUE(differs) << "perturbed rollouts rank the samples of the held frames differently";
}

TEST(RetargetMetrics, MatchHandComputedErrors) {
  const Quat z20(Eigen::AngleAxisd(0.2, Vec3::UnitZ())), z40(Eigen::AngleAxisd(0.4, Vec3::UnitZ()));
  const std::vector<Pose> ref = {{Quat::Identity(), Vec3(0, 0, 0)}, {Quat::Identity(), Vec3(1, 0, 0)},
                                 {Quat::Identity(), Vec3(0, 0, 0)}};
  const std::vector<Pose> sim = {{z20, Vec3(0.03, 0.04, 0)}, {z40, Vec3(1, 0.15, 0)},
                                 {Quat::Identity(), Vec3(5, 0, 0)}};
  TrackingMetrics m = ObjectTrackingMetrics(sim, ref, {true, true, false});
  EXPECT_NEAR(m.e_pos, 0.1, 1e-12);  // (0.05 + 0.15) / 2
  EXPECT_NEAR(m.e_rot, 0.3, 1e-12);
  EXPECT_EQ(m.frames, 2);
  EXPECT_FALSE(m.success);  // 0.1 is not < 0.1
  m = ObjectTrackingMetrics({sim[0]}, {ref[0]});
  EXPECT_NEAR(m.e_pos, 0.05, 1e-12);
  EXPECT_TRUE(m.success);
  EXPECT_NEAR(RotationError(Quat::Identity(), z40).z(), 0.4, 1e-12);
}

TEST(DynamicRetarget, SameSeedGivesTheSameTrajectoryForAnyThreadCount) {
  const recon::Reconstruction r = Reference();
  TempDir dir;
  // Perturbed rollouts in every held frame of this short lift.
  const auto config = [](int threads) {
    DynamicRetargetConfig c = SmallConfig(threads);
    c.sampler.perturb_gate_seconds = 0.02;
    c.sampler.perturb_prob = 1;
    return c;
  };
  const DynamicRetargetRun a = Retarget(r, config(2), dir);
  const DynamicRetargetRun b = Retarget(r, config(2), dir);
  const DynamicRetargetRun c = Retarget(r, config(1), dir);
  DynamicRetargetConfig other = config(2);
  other.sampler.seed = 4;
  const DynamicRetargetRun d = Retarget(r, other, dir);
  ASSERT_EQ(a.trajectory.qpos.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(a.trajectory.ctrl.size(), static_cast<size_t>(kFrames));
  EXPECT_GT(a.stats.rollouts, 0);
  bool differs = false;
  for (int f = 0; f < kFrames; ++f) {
    EXPECT_EQ(a.trajectory.qpos[f], b.trajectory.qpos[f]) << "frame " << f;
    EXPECT_EQ(a.trajectory.ctrl[f], b.trajectory.ctrl[f]) << "frame " << f;
    EXPECT_EQ(a.trajectory.qpos[f], c.trajectory.qpos[f]) << "frame " << f;
    EXPECT_EQ(a.trajectory.object_poses[f].t, c.trajectory.object_poses[f].t);
    differs |= a.trajectory.ctrl[f] != d.trajectory.ctrl[f];
  }
  EXPECT_TRUE(differs) << "another seed must draw other samples";
  const TrackingMetrics m = ObjectTrackingMetrics(a.trajectory.object_poses, FilledObjectPoses(r));
  EXPECT_EQ(a.metrics.e_pos, m.e_pos);
  EXPECT_EQ(a.trajectory.metrics["success"].get<bool>(), a.metrics.success);
}

TEST(DynamicRetarget, NanFramesAndBadMeshesAreNamedErrors) {
  TempDir dir;
  recon::Reconstruction r = Reference();
  r.right_joints[5](3, 1) = std::nan("");
  EXPECT_EQ(ErrorCode([&] { Retarget(r, SmallConfig(), dir); }), "bad_reference");
  r = Reference();
  r.object_poses[2].t.x() = std::nan("");
  try {
    Retarget(r, SmallConfig(), dir);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_reference");
    EXPECT_EQ(e.site().field, "object_poses");
    EXPECT_EQ(e.site().clip, "synthetic");
  }
  TriMesh empty = Cylinder();
  empty.faces.resize(0, 3);
  const DynamicRetargetConfig c = SmallConfig();
  EXPECT_EQ(ErrorCode([&] {
              RetargetReconstruction(Reference(), empty, FindEmbodiment(c.hand, c.robots_dir), c,
                                     dir / "scene", "synthetic");
            }),
            "bad_mesh");
}

// The synthetic reference's hand + cylinder scene in `dir` and the
// dynamic reference built on it (every frame resting).
struct SceneAndReference {
  HandModel hand;
  DynamicReference ref;
};

SceneAndReference BuildSceneAndReference(const DynamicRetargetConfig& c, const std::filesystem::path& dir) {
  const recon::Reconstruction r = Reference();
  const std::vector<Pose> object = FilledObjectPoses(r);
  const ObjectScene scene = BuildObjectScene(Cylinder(), object[0], c.scene, dir / "scene");
  std::ifstream in(scene.xml_path);
  const std::string xml((std::istreambuf_iterator<char>(in)), {});
  SceneAndReference out{BuildHandModel(FindEmbodiment(c.hand, c.robots_dir), xml, dir / "scene"), {}};
  KinematicRetargeter kinematic(out.hand, c.kinematic);
  const HandTrajectory t = kinematic.Solve(r.right_joints, r.right_valid, r.fps);
  out.ref = BuildReference(out.hand.model.get(), t, object, std::vector<uint8_t>(kFrames, 0),
                           std::vector<bool>(kFrames, true), 0.0);
  return out;
}

TEST(DynamicRetarget, AnUnstableSimulationIsANamedError) {
  TempDir dir;
  const DynamicRetargetConfig c = SmallConfig();
  const auto [hand, ref] = BuildSceneAndReference(c, dir.path());
  ModelPtr broken(mj_copyModel(nullptr, hand.model.get()));
  broken->opt.gravity[2] = -1e300;  // the state overflows in the first step
  EXPECT_EQ(ErrorCode([&] { RetargetDynamics(broken.get(), ref, c.sampler); }), "unstable_simulation");
}

// Position actuators lag a moving target by their damping (and the base
// sags under gravity); targets that lead by the reference's velocity,
// acceleration and the sag make the floating wrist follow it.
TEST(DynamicRetarget, FeedforwardTargetsMakeTheWristFollow) {
  TempDir dir;
  const auto [hand, ref] = BuildSceneAndReference(SmallConfig(), dir.path());
  const mjModel* m = hand.model.get();
  const SceneIndex index = IndexScene(m);
  // Mean distance of the simulated wrist from the reference's, driven by `targets`.
  auto wrist_error = [&](const RowMatrix& targets) {
    DataPtr d = MakeData(m);
    for (int a = 0; a < m->nu; ++a) d->qpos[index.act_qpos[a]] = ref.ctrl(0, a);
    mj_forward(m, d.get());
    double sum = 0;
    for (int s = 0; s < ref.steps(); ++s) {
      for (int a = 0; a < m->nu; ++a) d->ctrl[a] = targets(s, a);
      mj_step(m, d.get());
      Vec3 e = Vec3::Zero();
      for (int a = 0, k = 0; a < m->nu; ++a) {
        if (index.act_kind[a] == kBasePos) e[k++] = d->qpos[index.act_qpos[a]] - ref.ctrl(std::min(s + 1, ref.steps() - 1), a);
      }
      sum += e.norm();
    }
    return sum / ref.steps();
  };
  const double plain = wrist_error(ref.ctrl), led = wrist_error(ref.feedforward);
  std::printf("mean wrist lag: targets = reference %.2f mm, feed-forward %.2f mm\n", 1e3 * plain, 1e3 * led);
  EXPECT_LT(led, 0.5 * plain);
  EXPECT_LT(led, 0.008);
}

TEST(DynamicRetargetStage, WritesTheTrajectoryMetricsAndVerdict) {
  TempDir root;
  recon::Reconstruction r = Reference();
  SaveObj(Cylinder(), root / "cylinder.obj");
  r.object_mesh = root / "cylinder.obj";
  recon::WriteReconstruction(r, root / "artifacts/9" / recon::kReconStageName);
  ClipContext context;
  context.clip.id = 9;
  context.clip.external_id = "synthetic9";
  context.artifact_dir = root / "artifacts/9" / kRetargetStageName;
  stages::DynamicRetargetStage stage(SmallConfig());
  const StageResult result = stage.Run(context);
  const HandTrajectory t = ReadTrajectoryJson(context.artifact_dir / "trajectory.json");
  ASSERT_EQ(t.qpos.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(t.ctrl.size(), static_cast<size_t>(kFrames));
  EXPECT_EQ(t.ctrl_names.size(), t.ctrl[0].size());
  EXPECT_EQ(t.object_poses.size(), static_cast<size_t>(kFrames));
  const bool success = result.measurements["success"].get<bool>();
  EXPECT_EQ(t.metrics["success"].get<bool>(), success);
  EXPECT_EQ(result.verdict, success ? Verdict::kPass : Verdict::kReject);
  EXPECT_EQ(result.reason, success ? "" : stages::kReasonTrackingFailed);
  EXPECT_TRUE(std::filesystem::exists(context.artifact_dir / "robot_scene.xml"));
  EXPECT_TRUE(std::filesystem::exists(context.artifact_dir / "scene/scene.xml"));
  ReadTrajectoryJson(context.artifact_dir / "kinematic_reference.json");

  // Redecide from measurements alone: a 0.2 m position error rejects.
  Json m = result.measurements;
  m["e_pos"] = 0.2;
  EXPECT_EQ(stage.Redecide(m)->reason, stages::kReasonTrackingFailed);
  m["e_pos"] = 0.05;
  m["e_rot"] = 0.1;
  EXPECT_EQ(stage.Redecide(m)->verdict, Verdict::kPass);

  // Without an object mesh there is nothing to track.
  r.object_mesh.clear();
  recon::WriteReconstruction(r, root / "artifacts/10" / recon::kReconStageName);
  context.artifact_dir = root / "artifacts/10" / kRetargetStageName;
  const StageResult none = stage.Run(context);
  EXPECT_EQ(none.verdict, Verdict::kReject);
  EXPECT_EQ(none.reason, stages::kReasonNoObject);
}


// The ladder (sampler_ladder.h) on a lifting reference whose kinematic
// grasp holds the object (pinch, grasp terms pressing 1 cm in, a hollow
// object's density: the bench's synthetic setting). Rung "replay" executes
// the reference's own controls (no noise); rung "starved" draws four
// samples under a noise that opens the grip and scores them with a
// penetration penalty of no tolerance, so that any grip costs more than
// losing the object (the planner keeps the better of the samples' mean and
// the best sample, which is the nominal when the reward favours it).
TriMesh LadderCylinder() { return synth::MakeCylinder(0.03, 0.09, 16); }

recon::Reconstruction Lift(int frames) {
  synth::EpisodeSpec spec;
  spec.frames = frames;
  spec.verb = synth::Verb::kPickPlace;
  spec.grasp = synth::GraspType::kPinch;
  spec.manipulation_scale = 2;  // lifts of ~20 cm: an object left on the floor fails
  return synth::EpisodeReconstruction(synth::ScriptEpisode(spec, LadderCylinder()), 30.0);
}

DynamicRetargetConfig LadderRung(const std::string& rung) {
  DynamicRetargetConfig c = SmallConfig();
  c.kinematic.contact_weight = 16;
  c.kinematic.contact_depth = 0.01;
  c.scene.density = 400;
  AnnealedSamplerConfig& s = c.sampler;
  s.perturb = false;
  s.horizon = s.ctrl_dt = s.knot_dt = s.blend_seconds = 0.25;
  s.warmup_seconds = -1;
  if (rung == "replay") {
    s.num_samples = 2;
    s.max_num_iterations = 1;
    s.pos_noise_scale = s.rot_noise_scale = s.joint_noise_scale = 0;
  } else {
    s.num_samples = 4;
    s.max_num_iterations = 1;
    s.top_fraction = 1;
    s.temperature = 1e6;
    s.pos_noise_scale = 0.05;
    s.joint_noise_scale = 1.0;
    s.reward.penetration_tolerance = 0;
    s.reward.penetration_penalty_scale = 1e6;
  }
  return c;
}

TEST(SamplerLadder, AClipFailingAtTheFirstRungKeepsTheSecondRungsRunAndRecordsBoth) {
  TempDir dir;
  const recon::Reconstruction r = Lift(kLadderFrames);
  const std::function<DynamicRetargetRun(const std::string&)> track = [&](const std::string& rung) {
    const DynamicRetargetConfig c = LadderRung(rung);
    return RetargetReconstruction(r, LadderCylinder(), FindEmbodiment(c.hand, c.robots_dir), c, dir / "scene", "lift");
  };
  const LadderResult<DynamicRetargetRun> ladder = RunLadder(std::vector<std::string>{"starved", "replay"}, track);
  ASSERT_EQ(ladder.rungs.size(), 2u);
  EXPECT_EQ(ladder.rungs[0].name, "starved");
  ASSERT_FALSE(ladder.rungs[0].metrics.success) << "E_pos " << ladder.rungs[0].metrics.e_pos;
  ASSERT_TRUE(ladder.rungs[1].metrics.success) << "E_pos " << ladder.rungs[1].metrics.e_pos;
  EXPECT_EQ(ladder.best_rung, 1);
  const DynamicRetargetRun replay = track("replay");
  ASSERT_EQ(ladder.best.trajectory.qpos.size(), replay.trajectory.qpos.size());
  for (size_t f = 0; f < replay.trajectory.qpos.size(); ++f) {
    EXPECT_EQ(ladder.best.trajectory.qpos[f], replay.trajectory.qpos[f]) << "frame " << f;
  }
  Json m;
  WriteLadderMeasurements(ladder.rungs, ladder.best_rung, m);
  EXPECT_EQ(m[kMeasurementRung], "replay");
  EXPECT_EQ(m[kMeasurementRungsRun], 2);
  EXPECT_EQ(m[RungMeasurementKey("starved", kMetricSuccess)], false);
  EXPECT_EQ(m[RungMeasurementKey("replay", kMetricPositionError)].get<double>(), replay.metrics.e_pos);
  EXPECT_GT(m[RungMeasurementKey("starved", kRungSeconds)].get<double>(), 0);
}

TEST(SamplerLadder, RungsSharingOneSceneEndAsRungsBuildingTheirOwn) {
  // ClipRetarget builds the scene, model and kinematic reference once for
  // every rung (as the `retarget` stage does); each rung's run must be the
  // one RetargetReconstruction makes from scratch.
  TempDir dir;
  const recon::Reconstruction r = Lift(kLadderFrames);
  const TriMesh cylinder = LadderCylinder();
  const DynamicRetargetConfig base = LadderRung("replay");
  const ClipRetarget shared(r, cylinder, FindEmbodiment(base.hand, base.robots_dir), base, dir / "shared", "lift");
  for (const std::string rung : {"starved", "replay"}) {
    const DynamicRetargetConfig c = LadderRung(rung);
    const DynamicRetargetRun alone =
        RetargetReconstruction(r, cylinder, FindEmbodiment(c.hand, c.robots_dir), c, dir / rung, "lift");
    const DynamicRetargetRun reused = shared.Track(c.sampler);
    EXPECT_EQ(reused.metrics.e_pos, alone.metrics.e_pos) << rung;
    EXPECT_EQ(reused.stats.sim_steps, alone.stats.sim_steps) << rung;
    ASSERT_EQ(reused.trajectory.qpos.size(), alone.trajectory.qpos.size());
    for (size_t f = 0; f < alone.trajectory.qpos.size(); ++f) {
      EXPECT_EQ(reused.trajectory.qpos[f], alone.trajectory.qpos[f]) << rung << " frame " << f;
    }
  }
}

TEST(SamplerLadder, AClipSucceedingAtTheFirstRungRunsNoOther) {
  TempDir root;
  recon::Reconstruction r = Lift(kLadderFrames);
  SaveObj(LadderCylinder(), root / "cylinder.obj");
  r.object_mesh = root / "cylinder.obj";
  recon::WriteReconstruction(r, root / "artifacts/9" / recon::kReconStageName);
  ClipContext context;
  context.clip.id = 9;
  context.artifact_dir = root / "artifacts/9" / kRetargetStageName;
  DynamicRetargetConfig config = LadderRung("replay");
  config.preset = kLadderPreset;
  config.ladder = {kSamplerRung, "fast"};
  stages::DynamicRetargetStage stage(config);
  const StageResult result = stage.Run(context);
  const Json& m = result.measurements;
  ASSERT_TRUE(m[kMetricSuccess].get<bool>());
  EXPECT_EQ(m[kMeasurementRung], kSamplerRung);
  EXPECT_EQ(m[kMeasurementRungsRun], 1);
  EXPECT_TRUE(m.contains(RungMeasurementKey(kSamplerRung, kRungSeconds)));
  EXPECT_FALSE(m.contains(RungMeasurementKey("seed", kRungSeconds)));
  EXPECT_EQ(result.verdict, Verdict::kPass);
}

TEST(SamplerLadder, TheConfigNamesItsRungs) {
  DynamicRetargetConfig c;
  EXPECT_EQ(LadderRungs(c), (std::vector<std::string>{"fast", "medium", "seed"}));
  c.preset = "fast";
  EXPECT_EQ(LadderRungs(c), std::vector<std::string>{"fast"});
  c.preset = "";
  EXPECT_EQ(LadderRungs(c), std::vector<std::string>{kSamplerRung});
  c.sampler.num_samples = 7;
  EXPECT_EQ(EffectiveSampler(c).num_samples, 7);
  c.preset = kLadderPreset;
  c.sampler.threads = 1;
  EXPECT_EQ(RungSampler(c, "medium").threads, 1);
  EXPECT_EQ(RungSampler(c, "medium").num_samples, SamplerPreset("medium").num_samples);
  c.ladder = {"fast", "turbo"};
  try {
    stages::DynamicRetargetStage stage(c);
    ADD_FAILURE() << "an unknown rung must be refused";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_config");
    EXPECT_EQ(e.site().field, "retarget.ladder");
  }
  c.ladder = {};
  EXPECT_EQ(ErrorCode([&] { stages::DynamicRetargetStage stage(c); }), "bad_config");
  // The ladder is a parameter: another ladder hashes differently.
  DynamicRetargetConfig a, b;
  b.ladder = {"fast", "seed"};
  EXPECT_NE(ParamHash(stages::DynamicRetargetStage(a).Params()), ParamHash(stages::DynamicRetargetStage(b).Params()));
  // Issue 51's fixes are revision 2: a result recorded under the
  // parameters' hash alone (every run before them) no longer matches, so
  // `run` makes it again; revision 1 stages keep their old hashes.
  const stages::DynamicRetargetStage fixed(a);
  EXPECT_EQ(fixed.Revision(), 2);
  EXPECT_NE(stages::ResultHash(fixed), ParamHash(fixed.Params()));
  const stages::KinematicStage kinematic;
  EXPECT_EQ(stages::ResultHash(kinematic), ParamHash(kinematic.Params()));
}


// Issue 51's ground truth: deploy_plans_bench's reference 0 (a 10-s
// pick-and-place of a cylinder lifting it 16 cm at 4.0-4.6 s), cut after
// the lift at 5.5 s. The open-loop replay of its kinematic reference lifts
// the object, so the `fast` preset, whose nominal that replay is, must end
// lifted too. It did not: the transition reward asked the object to touch
// the floor while the reference lifted it through the rest band, and the
// planner executed a never simulated mean of samples that opened the grip.
TEST(DynamicRetarget, AReferenceWhoseReplayLiftsTheObjectEndsLifted) {
  const TriMesh cylinder = synth::MakeCylinder(0.03, 0.09, 16);
  synth::EpisodeSpec spec;
  spec.verb = synth::Verb::kPickPlace;
  spec.frames = 300;
  spec.manipulation_scale = 2.0;
  spec.approach_elevation = 0.55;
  spec.grasp = synth::GraspType::kPinch;
  spec.approach_azimuth = -0.35;
  recon::Reconstruction r = synth::EpisodeReconstruction(synth::ScriptEpisode(spec, cylinder), 30.0);
  const int frames = 165;
  r.right_valid.resize(frames), r.right_joints.resize(frames);
  r.object_valid.resize(frames), r.object_poses.resize(frames);
  ASSERT_GT(r.object_poses.back().t.z() - r.object_poses.front().t.z(), 0.12) << "the reference lifts";

  DynamicRetargetConfig c = SmallConfig();
  c.kinematic.contact_weight = 16;  // deploy_plans_bench's FastConfig
  c.kinematic.contact_depth = 0.01;
  c.scene.density = 400;
  c.sampler = SamplerPreset("fast");
  c.sampler.threads = 2;
  TempDir dir;
  const ClipRetarget clip(r, cylinder, FindEmbodiment(c.hand, c.robots_dir), c, dir / "scene", "lift");
  AnnealedSamplerConfig replay = c.sampler;  // the nominal alone: no noise, one iteration
  replay.num_samples = 2;
  replay.max_num_iterations = 1;
  replay.pos_noise_scale = replay.rot_noise_scale = replay.joint_noise_scale = 0;
  const double top = r.object_poses.back().t.z();
  const DynamicRetargetRun open_loop = clip.Track(replay);
  ASSERT_NEAR(open_loop.trajectory.object_poses.back().t.z(), top, 0.03) << "the replay lifts the object";
  const DynamicRetargetRun fast = clip.Track(c.sampler);
  EXPECT_NEAR(fast.trajectory.object_poses.back().t.z(), top, 0.03) << "E_pos " << fast.metrics.e_pos;
  EXPECT_TRUE(fast.metrics.success) << "E_pos " << fast.metrics.e_pos;
}

}  // namespace
}  // namespace doasido::retarget
