// The kinematic retargeting's grasp terms (kinematic_retarget.h) and the
// object surface they measure (object_surface.h): signed distances against
// a box whose answer is known, then a synthetic pick-and-place reference
// (synth module) retargeted with and without the terms.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "core/file_text.h"
#include "eval/reconstruction_noise.h"
#include "eval/reference_hold.h"
#include "retarget/dynamic/bimanual_retarget.h"
#include "retarget/dynamic/dynamic_reference.h"
#include "retarget/kinematic/kinematic_retarget.h"
#include "retarget/scene/object_surface.h"
#include "retarget/scene/scene_builder.h"
#include "synth/episode.h"
#include "synth/objects.h"
#include "tests/small_retarget_config.h"
#include "tests/test_util.h"

namespace doasido::retarget {
namespace {

using doasido::testing::ErrorCode;
using doasido::testing::SharedData;
using doasido::testing::TempDir;

HandModel HandWithObject(const TriMesh& mesh, const Pose& pose, const TempDir& dir,
                         double density = SceneConfig().density) {
  SceneConfig scene;
  scene.density = density;
  scene.place_on_floor = false;
  scene.settle_seconds = 0;
  const ObjectScene s = BuildObjectScene(mesh, pose, scene, dir / "scene");
  return BuildHandModel(FindEmbodiment("sharpa_right", (SharedData() / "robots").string()),
                        ReadFileOrThrow(s.xml_path, "io", "cannot read the scene"), dir / "scene");
}

// A 40-frame synthetic pick-and-place of a cylinder (3 cm, 9 cm tall), its
// object poses, and the right Sharpa hand in a scene with the object.
struct PickPlace {
  explicit PickPlace(const TempDir& dir)
      : cylinder(synth::MakeCylinder(0.03, 0.09, 16)),
        r(synth::EpisodeReconstruction(synth::ScriptEpisode(Spec(), cylinder), 30.0)),
        object(FilledObjectPoses(r)),
        hand(HandWithObject(cylinder, object[0], dir)) {}
  static synth::EpisodeSpec Spec() {
    synth::EpisodeSpec spec;
    spec.frames = 40;
    return spec;
  }
  TriMesh cylinder;
  recon::Reconstruction r;
  std::vector<Pose> object;
  HandModel hand;
};

// A 16-sided cylinder (radius 3 cm to its corners, 9 cm tall), dilated by
// the scene's 2 mm: at its centre, minus the distance to the side faces;
// above the top, the height over it, straight up; beside it, the distance
// to the nearest side face, horizontally.
TEST(ObjectSurface, SignedDistanceOfADilatedCylinder) {
  TempDir dir;
  const Pose pose{Quat(Eigen::AngleAxisd(0.3, Vec3::UnitX())), Vec3(0.1, 0.2, 0.05)};
  const HandModel hand = HandWithObject(synth::MakeCylinder(0.03, 0.09, 16), pose, dir);
  const mjModel* m = hand.model.get();
  DataPtr d = MakeData(m);
  mj_kinematics(m, d.get());
  const ObjectSurface surface(m, NameToId(m, mjOBJ_BODY, "object"));
  ASSERT_FALSE(surface.empty());
  const double apothem = 0.03 * std::cos(M_PI / 16), dilation = 0.002;
  EXPECT_NEAR(surface.SignedDistance(d.get(), pose * Vec3(0, 0, 0.045)), -(apothem + dilation), 2e-4);
  Vec3 gradient;
  EXPECT_NEAR(surface.SignedDistance(d.get(), pose * Vec3(0.005, -0.01, 0.09 + dilation + 0.01), &gradient),
              0.01, 2e-4);
  EXPECT_LT((gradient - pose.q * Vec3::UnitZ()).norm(), 1e-6);
  // 4.2 cm from the axis: between the distance to a side face seen along
  // a corner's direction and along the face's own normal.
  const double x = 0.03 + dilation + 0.01;
  const double beside = surface.SignedDistance(d.get(), pose * Vec3(x, 0, 0.03), &gradient);
  EXPECT_GT(beside, x * std::cos(M_PI / 16) - apothem - dilation - 3e-4);
  EXPECT_LT(beside, x - apothem - dilation + 3e-4);
  EXPECT_NEAR((pose.q.inverse() * gradient).z(), 0.0, 1e-9);
}

// A grasping reference retargeted with the grasp terms: every fingertip
// geom asked to touch sits contact_depth into the object (within a
// millimetre on average), no other hand geom goes further in than the
// tolerance; without the terms the same fingertips stay outside.
TEST(KinematicGrasp, TouchingFingertipsReachTheObjectAndTheRestStayOut) {
  TempDir dir;
  const PickPlace scene(dir);
  const recon::Reconstruction& r = scene.r;
  const std::vector<Pose>& object = scene.object;
  const HandModel& hand = scene.hand;
  KinematicConfig config;
  config.restarts = 1;
  config.contact_weight = 16;
  config.contact_depth = 0.003;
  struct Gaps {
    double touching_mean = 0, kept_out_min = 1;
    int touching = 0, frames = 0;
  };
  auto measure = [&](const KinematicConfig& c) {
    KinematicRetargeter kinematic(hand, c);
    std::vector<int> contacts;
    const HandTrajectory t = kinematic.Solve(r.right_joints, r.right_valid, r.fps, {}, &object, &contacts);
    // The terms of the on-configuration decide which geoms are compared.
    KinematicConfig on = c;
    on.contact_weight = 16;
    KinematicRetargeter judge(hand, on);
    judge.set_scale(t.scale);
    Gaps g;
    for (int f = 0; f < r.frames(); ++f) {
      if (!r.right_valid[f] || judge.PoseObject(r.right_joints[f], object[f]) == 0) continue;
      ++g.frames;
      for (const auto& gap : judge.GraspGaps(t.qpos[f])) {
        if (gap.touch) {
          g.touching_mean += gap.distance;
          ++g.touching;
        } else {
          g.kept_out_min = std::min(g.kept_out_min, gap.distance);
        }
      }
    }
    g.touching_mean /= std::max(1, g.touching);
    return g;
  };
  const Gaps on = measure(config);
  KinematicConfig off_config = config;
  off_config.contact_weight = 0;
  const Gaps off = measure(off_config);
  std::printf("grasp frames %d, touching fingertip geoms %d: mean distance with terms %.2f mm, "
              "without %.2f mm; deepest other geom with %.2f mm, without %.2f mm\n",
              on.frames, on.touching, 1e3 * on.touching_mean, 1e3 * off.touching_mean,
              1e3 * on.kept_out_min, 1e3 * off.kept_out_min);
  ASSERT_GT(on.frames, 5);
  ASSERT_GT(on.touching, 2 * on.frames);
  EXPECT_NEAR(on.touching_mean, -config.contact_depth, 0.001);
  EXPECT_GT(off.touching_mean, on.touching_mean + 0.001);
  EXPECT_GT(on.kept_out_min, -0.002);
}

// A lone fingertip on the object is not pressed into it (it would push a
// free object away): at a frame where the reference pinches, the grasp
// terms press two or more fingertips; with every human keypoint but the
// fingertip nearest the object moved 10 cm away, none.
TEST(KinematicGrasp, ALoneFingertipIsNotPressedIntoTheObject) {
  TempDir dir;
  const PickPlace s(dir);
  KinematicConfig config;
  config.contact_weight = 16;
  KinematicRetargeter kinematic(s.hand, config);
  int pinch = -1, pressed = 0;
  for (int f = 0; f < s.r.frames() && pinch < 0; ++f) {
    pressed = s.r.right_valid[f] ? kinematic.PoseObject(s.r.right_joints[f], s.object[f]) : 0;
    if (pressed >= kMinGraspFingertips) pinch = f;
  }
  ASSERT_GE(pinch, 0) << "the reference never pinches";
  auto touching = [&] {
    const auto gaps = kinematic.GraspGaps(Eigen::VectorXd::Zero(kinematic.VariableNames().size()));
    return std::count_if(gaps.begin(), gaps.end(), [](const auto& g) { return g.touch; });
  };
  EXPECT_EQ(touching(), pressed);
  Keypoints21 lone = s.r.right_joints[pinch];
  int nearest = 4;  // the human fingertip nearest the object
  for (int tip : {8, 12, 16, 20}) {
    if (kinematic.ObjectDistance(lone.row(tip).transpose()) < kinematic.ObjectDistance(lone.row(nearest).transpose())) {
      nearest = tip;
    }
  }
  ASSERT_LT(kinematic.ObjectDistance(lone.row(nearest).transpose()), config.contact_epsilon);
  for (int k = 0; k < 21; ++k) {
    if (k != nearest) lone.row(k) += Eigen::RowVector3d(0, 0, 0.1);
  }
  EXPECT_EQ(kinematic.PoseObject(lone, s.object[pinch]), 0);
  EXPECT_EQ(touching(), 0);
}

// Whether a kinematic reference's grasp holds its object (reference_hold.h):
// a synthetic pick-and-place, the object lifted 8 cm, retargeted with the
// grasp terms pressing touching fingertips 1 cm in; at the highest frame a
// pinch (thumb against index and middle) holds a hollow 100-g cylinder for
// a second, a wrap (fingers on one flank, thumb on the rim) drops it, as
// does the pinch without the grasp terms.
TEST(KinematicGrasp, APinchedReferenceHoldsALightObjectAWrapDropsIt) {
  const TriMesh cylinder = synth::MakeCylinder(0.03, 0.09, 16);
  auto drop = [&](synth::GraspType grasp, double contact_weight) {
    TempDir dir;
    synth::EpisodeSpec spec;
    spec.frames = 40;
    spec.grasp = grasp;
    const recon::Reconstruction r = synth::EpisodeReconstruction(synth::ScriptEpisode(spec, cylinder), 30.0);
    const std::vector<Pose> object = FilledObjectPoses(r);
    const HandModel hand = HandWithObject(cylinder, object[0], dir, 400);
    KinematicConfig config;
    config.restarts = 1;
    config.contact_weight = contact_weight;
    config.contact_depth = 0.01;
    KinematicRetargeter kinematic(hand, config);
    const HandTrajectory t = kinematic.Solve(r.right_joints, r.right_valid, r.fps, {}, &object, nullptr);
    int top = 0;
    for (int f = 0; f < r.frames(); ++f) {
      if (object[f].t.z() > object[top].t.z()) top = f;
    }
    EXPECT_GT(object[top].t.z() - object[0].t.z(), 0.07);
    DataPtr d = MakeData(hand.model.get());
    return ReferenceHoldDrop(hand.model.get(), d.get(), t, top, object[top], 1.0);
  };
  const double pinch = drop(synth::GraspType::kPinch, 16), wrap = drop(synth::GraspType::kWrap, 16),
               bare = drop(synth::GraspType::kPinch, 0);
  std::printf("object fell in 1 s: pinch %.1f mm, wrap %.1f mm, pinch without grasp terms %.1f mm\n",
              1e3 * pinch, 1e3 * wrap, 1e3 * bare);
  EXPECT_LT(pinch, 0.02);
  EXPECT_GT(wrap, 0.05);
  EXPECT_GT(bare, 0.05);
}

// A synthetic handover (synth ScriptHandover) through its reconstruction:
// labelled in-hand per hand as the retargeting labels frames, the right hand
// touches the object first and the left hand last, the two hold it together
// in between, and the labels follow the episode's exact contact flags.
TEST(Bimanual, AHandoverTouchesTheRightHandFirstAndTheLeftLast) {
  const TriMesh cylinder = synth::MakeCylinder(0.03, 0.09, 16);
  synth::EpisodeSpec spec;
  spec.frames = 90;
  spec.two_hand_task = synth::TwoHandTask::kHandover;
  const synth::Episode episode = synth::ScriptEpisode(spec, cylinder);
  const recon::Reconstruction r = synth::EpisodeReconstruction(episode, 30.0);
  ASSERT_EQ(r.left_valid.size(), 90u);
  const double epsilon = 0.02;
  const std::vector<bool> right = LabelInHand(r.right_joints, r.right_valid, r.object_poses, cylinder, epsilon);
  const std::vector<bool> left = LabelInHand(r.left_joints, r.left_valid, r.object_poses, cylinder, epsilon);
  const auto first = [](const std::vector<bool>& v) { return int(std::find(v.begin(), v.end(), true) - v.begin()); };
  const auto last = [](const std::vector<bool>& v) { return int(v.rend() - std::find(v.rbegin(), v.rend(), true)) - 1; };
  int both = 0, agree = 0, contacts = 0;
  for (int t = 0; t < 90; ++t) {
    both += right[t] && left[t];
    for (int side = 0; side < 2; ++side) {
      const bool truth = episode.frames[t].contact[side];
      const bool label = side == static_cast<int>(synth::Side::kRight) ? right[t] : left[t];
      contacts += truth;
      agree += truth && label;
    }
  }
  std::printf("handover: right touches frames %d-%d, left %d-%d, both %d frames; %d of %d true contacts labelled\n",
              first(right), last(right), first(left), last(left), both, agree, contacts);
  EXPECT_LT(first(right), first(left));
  EXPECT_GT(last(left), last(right));
  EXPECT_GT(both, 0);
  EXPECT_EQ(agree, contacts) << "every frame a hand holds the object is labelled in-hand";
  // The object ends 22 cm to the left of where it started, on the table.
  EXPECT_NEAR((r.object_poses.back().t - r.object_poses.front().t).norm(), std::hypot(0.22, 0.02), 1e-9);
}

// Both hands and the object in one simulation (bimanual_retarget.h) on a
// synthetic two-handed carry: each robot hand on its own wrist following its
// own hand's reference, the same trajectory for the same seed.
TEST(Bimanual, ACarryIsRetargetedWithBothHandsInOneScene) {
  TempDir dir;
  const TriMesh cylinder = synth::MakeCylinder(0.035, 0.12, 16);
  synth::EpisodeSpec spec;
  spec.frames = 30;
  spec.two_hand_task = synth::TwoHandTask::kCarry;
  const recon::Reconstruction r = synth::EpisodeReconstruction(synth::ScriptEpisode(spec, cylinder), 30.0);
  const DynamicRetargetConfig config = testing::SmallRetargetConfig();
  const Embodiment left = FindEmbodiment("sharpa_left", config.robots_dir);
  const Embodiment right = FindEmbodiment("sharpa_right", config.robots_dir);
  const BimanualRun run = RetargetBimanual(r, cylinder, left, right, config, dir / "scene", "carry");
  std::printf("bimanual carry: object E_pos %.3f m, E_rot %.3f rad, success %d; wrist error left %.1f mm, "
              "right %.1f mm; in-hand frames left %d, right %d; %lld sim steps\n",
              run.metrics.e_pos, run.metrics.e_rot, int(run.metrics.success), 1e3 * run.left_wrist_error,
              1e3 * run.right_wrist_error, run.left_in_hand_frames, run.right_in_hand_frames, run.stats.sim_steps);
  const ModelPtr m = CompileMjcfText(run.robot_scene_xml, (dir / "both.xml").string());
  EXPECT_EQ(m->nu, 2 * BuildHandModel(right).model->nu);
  ASSERT_EQ(run.trajectory.qpos.size(), 30u);
  for (const char* prefix : {kLeftPrefix, kRightPrefix}) {
    const auto& names = run.trajectory.qpos_names;
    EXPECT_NE(std::find(names.begin(), names.end(), std::string(prefix) + kWristJoints[0]), names.end());
  }
  for (const Eigen::VectorXd& q : run.trajectory.qpos) EXPECT_TRUE(q.allFinite());
  EXPECT_GT(run.left_in_hand_frames, 5);
  EXPECT_GT(run.right_in_hand_frames, 5);
  // The wrists wander under a handful of samples (one hand alone does too),
  // but each stays with its own hand's reference: the hands stand ~25 cm
  // apart, so a hand on the other's wrist would be off by more than that.
  EXPECT_LT(run.left_wrist_error, 0.15);
  EXPECT_LT(run.right_wrist_error, 0.15);
  // The two-hand trajectory splits into each hand's own: names without
  // their prefix, the same positions; combining the halves gives it back.
  const auto [l, rt] = SplitBimanualTrajectory(run.trajectory);
  EXPECT_EQ(l.embodiment, "sharpa_left");
  EXPECT_EQ(rt.embodiment, "sharpa_right");
  EXPECT_EQ(l.qpos_names, run.left_kinematic.qpos_names);
  EXPECT_EQ(rt.ctrl_names.size() + l.ctrl_names.size(), run.trajectory.ctrl_names.size());
  const HandTrajectory rejoined = CombineBimanualTrajectories(l, rt);
  EXPECT_EQ(rejoined.qpos_names, run.trajectory.qpos_names);
  for (size_t t = 0; t < run.trajectory.qpos.size(); ++t) EXPECT_EQ(rejoined.qpos[t], run.trajectory.qpos[t]);
  EXPECT_EQ(ErrorCode([&] { SplitBimanualTrajectory(run.left_kinematic); }), "bad_trajectory");
  const BimanualRun again = RetargetBimanual(r, cylinder, left, right, config, dir / "scene2", "carry");
  for (size_t t = 0; t < run.trajectory.qpos.size(); ++t) {
    EXPECT_EQ(again.trajectory.qpos[t], run.trajectory.qpos[t]) << "frame " << t;
  }
}

}  // namespace
}  // namespace doasido::retarget
