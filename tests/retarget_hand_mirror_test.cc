// Mirroring a hand (hand_mirror.h) against its definition: at any joint
// configuration every body, geom and site of the mirrored model sits at
// S p with orientation S R S, where p, R are the original's (S flips one
// axis); mirroring twice gives the original; the built-in sharpa_right
// mirrors into the hand-drawn sharpa_left; the menagerie's Shadow hand
// (meshes, default classes) mirrors into a left hand the hand checker
// accepts, its description's points mirrored with it.
#include <random>

#include <gtest/gtest.h>
#include <tinyxml2.h>

#include "core/error.h"
#include "core/file_text.h"
#include "robot/embodiment.h"
#include "robot/hand_check.h"
#include "robot/hand_mirror.h"
#include "robot/mj_model.h"
#include "robot/mjcf_compat.h"
#include "robot/mjcf_text.h"
#include "robot/urdf_import.h"
#include "tests/test_util.h"
#include "tests/two_finger_hand.h"

namespace doasido::retarget {
namespace {

using doasido::testing::SharedData;
using doasido::testing::TempDir;
using RowMat3 = Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>;

Embodiment Hand(const std::string& name) { return FindEmbodiment(name, SharedData() / "robots"); }

ModelPtr Compile(const std::string& xml) { return CompileMjcfText(xml, "mirror_test.xml"); }

std::string Prepared(const Embodiment& hand) { return PrepareMjcf(hand.model_path).xml; }

Mat3 Flip(int axis) {
  Mat3 s = Mat3::Identity();
  s(axis, axis) = -1;
  return s;
}

// Sets the same random in-range angle on the joints of the same name.
void RandomPose(const mjModel* a, mjData* da, const mjModel* b, mjData* db, std::mt19937& rng) {
  for (int j = 0; j < a->njnt; ++j) {
    const double lo = a->jnt_limited[j] ? a->jnt_range[2 * j] : -1, hi = a->jnt_limited[j] ? a->jnt_range[2 * j + 1] : 1;
    const double q = std::uniform_real_distribution<double>(lo, hi)(rng);
    da->qpos[a->jnt_qposadr[j]] = q;
    const int jb = NameToId(b, mjOBJ_JOINT, mj_id2name(a, mjOBJ_JOINT, j));
    ASSERT_GE(jb, 0) << mj_id2name(a, mjOBJ_JOINT, j);
    db->qpos[b->jnt_qposadr[jb]] = q;
  }
  mj_kinematics(a, da);
  mj_kinematics(b, db);
}

// Worst deviation of `mirrored` from S (original) over bodies, geoms and
// sites at 5 random poses: positions (m) and orientations (Frobenius norm;
// of a mesh geom's orientation nothing is compared, as the compiler picks a
// mesh's principal axes up to sign; of a capsule's or cylinder's only its
// axis, as the compiler picks the spin of a frame given by fromto).
struct Deviation {
  double position = 0, rotation = 0;
};
Deviation MirrorDeviation(const mjModel* original, const mjModel* mirrored, int axis) {
  const Mat3 s = Flip(axis);
  DataPtr d0 = MakeData(original), d1 = MakeData(mirrored);
  std::mt19937 rng(5);
  Deviation worst;
  auto compare = [&](const mjtNum* p0, const mjtNum* p1, const mjtNum* r0, const mjtNum* r1,
                     bool axis_only = false) {
    worst.position = std::max(worst.position, (Eigen::Map<const Vec3>(p1) - s * Eigen::Map<const Vec3>(p0)).norm());
    if (!r0) return;
    const Mat3 a = Eigen::Map<const RowMat3>(r0), b = Eigen::Map<const RowMat3>(r1);
    const Mat3 diff = b - s * a * s;
    const Vec3 z = (s * a * s).col(2);  // up to sign: a capsule has no front end
    const double axis_gap = std::min((b.col(2) - z).norm(), (b.col(2) + z).norm());
    worst.rotation = std::max(worst.rotation, axis_only ? axis_gap : diff.norm());
  };
  for (int trial = 0; trial < 5; ++trial) {
    RandomPose(original, d0.get(), mirrored, d1.get(), rng);
    for (int b = 0; b < original->nbody; ++b) {
      compare(d0->xpos + 3 * b, d1->xpos + 3 * b, d0->xmat + 9 * b, d1->xmat + 9 * b);
    }
    for (int g = 0; g < original->ngeom; ++g) {
      const int type = original->geom_type[g];
      compare(d0->geom_xpos + 3 * g, d1->geom_xpos + 3 * g, type == mjGEOM_MESH ? nullptr : d0->geom_xmat + 9 * g,
              d1->geom_xmat + 9 * g, type == mjGEOM_CAPSULE || type == mjGEOM_CYLINDER);
    }
    for (int i = 0; i < original->nsite; ++i) {
      compare(d0->site_xpos + 3 * i, d1->site_xpos + 3 * i, d0->site_xmat + 9 * i, d1->site_xmat + 9 * i);
    }
  }
  return worst;
}

// Every orientation and position attribute MJCF has, in degrees and a
// custom euler sequence, on hinge and slide joints, with a full inertia.
constexpr const char* kEveryAttribute = R"(<mujoco>
  <compiler angle="degree" eulerseq="zXy"/>
  <default>
    <joint axis="0.3 0.9 0.1" limited="true" range="-40 70"/>
    <default class="slider"><joint type="slide" axis="0.2 0.7 0.4" limited="true" range="-0.02 0.03"/></default>
  </default>
  <worldbody>
    <body name="palm" pos="0.01 0.02 0.03" euler="10 -25 40">
      <inertial pos="0.001 0.002 0.003" mass="0.3" fullinertia="0.004 0.005 0.006 0.0004 -0.0003 0.0002"/>
      <geom type="box" size="0.02 0.03 0.01" axisangle="0.2 0.5 0.8 33"/>
      <site name="s0" pos="0.01 -0.01 0.02" xyaxes="0.6 0.8 0 -0.8 0.6 0.3"/>
      <body name="f1" pos="0.02 0.03 0.04" quat="0.9 0.1 -0.3 0.2">
        <joint name="j1"/>
        <geom type="capsule" fromto="0 0 0 0.01 0.02 0.05" size="0.008"/>
        <body name="f2" pos="0 0.01 0.05" zaxis="0.2 0.3 0.9">
          <joint name="j2" class="slider"/>
          <joint name="j3" axis="0.1 -0.2 0.95" range="-10 80"/>
          <geom type="sphere" size="0.01" pos="0.003 0.004 0.005"/>
          <site name="tip" pos="0.001 0.002 0.03" euler="5 6 7"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>)";

TEST(HandMirror, EveryFrameIsReflectedForEveryAxis) {
  const ModelPtr original = Compile(kEveryAttribute);
  for (const char axis : {'x', 'y', 'z'}) {
    const ModelPtr mirrored = Compile(MirrorMjcf(kEveryAttribute, axis, "every_attribute"));
    const Deviation d = MirrorDeviation(original.get(), mirrored.get(), axis - 'x');
    EXPECT_LT(d.position, 1e-9) << axis;
    EXPECT_LT(d.rotation, 1e-9) << axis;
    // Mass properties of the reflected body: the same mass, inertia S I S.
    const int palm = NameToId(mirrored.get(), mjOBJ_BODY, "palm");
    EXPECT_NEAR(mirrored->body_mass[palm], original->body_mass[palm], 1e-12);
  }
  EXPECT_EQ(doasido::testing::ErrorCode([] { MirrorMjcf(kEveryAttribute, 'w', "x"); }), "bad_config");
  EXPECT_EQ(doasido::testing::ErrorCode([] {
              MirrorMjcf("<mujoco><worldbody><body pos=\"1 2\"/></worldbody></mujoco>", 'y', "short.xml");
            }),
            "bad_mjcf");
}

TEST(HandMirror, MirroringTwiceGivesTheOriginal) {
  for (const char* name : {"sharpa_right", "shadow_right", "allegro_right"}) {
    const std::string xml = Prepared(Hand(name));
    const ModelPtr original = Compile(xml);
    const ModelPtr twice = Compile(MirrorMjcf(MirrorMjcf(xml, 'y', name), 'y', name));
    ASSERT_EQ(twice->nbody, original->nbody);
    ASSERT_EQ(twice->nmeshvert, original->nmeshvert);
    DataPtr d0 = MakeData(original.get()), d1 = MakeData(twice.get());
    std::mt19937 rng(9);
    RandomPose(original.get(), d0.get(), twice.get(), d1.get(), rng);
    double worst = 0;
    for (int i = 0; i < 3 * original->nsite; ++i) worst = std::max(worst, std::abs(d0->site_xpos[i] - d1->site_xpos[i]));
    for (int i = 0; i < 3 * original->ngeom; ++i) worst = std::max(worst, std::abs(d0->geom_xpos[i] - d1->geom_xpos[i]));
    for (int i = 0; i < 3 * original->nmeshvert; ++i) {
      worst = std::max(worst, double(std::abs(original->mesh_vert[i] - twice->mesh_vert[i])));
    }
    EXPECT_LT(worst, 1e-6) << name;
  }
}

// sharpa_left was drawn as sharpa_right mirrored through y = 0.
TEST(HandMirror, SharpaRightMirrorsIntoSharpaLeft) {
  const ModelPtr right = Compile(Prepared(Hand("sharpa_right")));
  const ModelPtr mirrored = Compile(MirrorMjcf(Prepared(Hand("sharpa_right")), 'y', "sharpa_right"));
  const ModelPtr left = Compile(Prepared(Hand("sharpa_left")));
  const Deviation from_right = MirrorDeviation(right.get(), mirrored.get(), 1);
  EXPECT_LT(from_right.position, 1e-9);
  EXPECT_LT(from_right.rotation, 1e-9);
  const Deviation from_left = MirrorDeviation(right.get(), left.get(), 1);
  EXPECT_LT(from_left.position, 1e-6);
  EXPECT_LT(from_left.rotation, 1e-5);
}

// World position of a description point in `m` with kinematics `d`.
Vec3 DescribedPoint(const mjModel* m, const mjData* d, const EmbodimentPoint& p) {
  const bool site = !p.site.empty();
  const int id = NameToId(m, site ? mjOBJ_SITE : mjOBJ_BODY, site ? p.site : p.body);
  const mjtNum* pos = site ? d->site_xpos + 3 * id : d->xpos + 3 * id;
  const mjtNum* mat = site ? d->site_xmat + 9 * id : d->xmat + 9 * id;
  return Eigen::Map<const Vec3>(pos) + Eigen::Map<const RowMat3>(mat) * Vec3(p.pos[0], p.pos[1], p.pos[2]);
}

// The menagerie's Shadow hand: meshes scaled through a default class,
// points with offsets. The mirrored description loads, passes the hand
// check, and its points sit where the right hand's do, reflected.
TEST(HandMirror, ShadowMirrorsIntoALeftHandThatPassesTheCheck) {
  TempDir dir;
  const Embodiment right = Hand("shadow_right");
  const MirroredHand left = MirrorHand(right, dir.path());
  EXPECT_EQ(left.description.filename(), "shadow_left.json");
  const Embodiment loaded = LoadEmbodiment(left.description);
  EXPECT_EQ(loaded.side, "left");
  EXPECT_EQ(loaded.name, "shadow_left");
  const HandCheck check = CheckHand(left.description);
  for (const HandProblem& p : check.problems) ADD_FAILURE() << p.code << ": " << p.message;
  EXPECT_EQ(check.structure.chains.size(), CheckHand(right).structure.chains.size());

  const ModelPtr original = Compile(Prepared(right));
  const ModelPtr mirrored = Compile(Prepared(loaded));
  const Deviation d = MirrorDeviation(original.get(), mirrored.get(), 1);
  EXPECT_LT(d.position, 1e-6);
  EXPECT_LT(d.rotation, 1e-6);
  DataPtr d0 = MakeData(original.get()), d1 = MakeData(mirrored.get());
  std::mt19937 rng(3);
  RandomPose(original.get(), d0.get(), mirrored.get(), d1.get(), rng);
  ASSERT_EQ(loaded.points.size(), right.points.size());
  for (size_t i = 0; i < right.points.size(); ++i) {
    const Vec3 a = DescribedPoint(original.get(), d0.get(), right.points[i]);
    const Vec3 b = DescribedPoint(mirrored.get(), d1.get(), loaded.points[i]);
    EXPECT_LT((b - Flip(1) * a).norm(), 1e-6) << "point " << i;
  }
  // The description mirrored twice is the original.
  const Embodiment back = MirrorEmbodiment(loaded, 'y', MirroredName(loaded.name), right.model);
  EXPECT_EQ(back.name, right.name);
  EXPECT_EQ(back.side, right.side);
  EXPECT_EQ(Json(back), Json(right));
  EXPECT_EQ(MirroredName("shadow_left"), "shadow_right");
  EXPECT_EQ(MirroredName("gripper"), "gripper_mirrored");
}

// A hand imported from URDF (meshes converted, description generated)
// mirrors like one written in MJCF.
TEST(HandMirror, AnImportedUrdfHandMirrorsAndPassesTheCheck) {
  TempDir dir;
  const ImportedHand imported = ImportUrdf(doasido::testing::WriteTwoFingerHand(dir.path() / "src"), dir / "out");
  const Embodiment right = LoadEmbodiment(imported.description);
  const MirroredHand left = MirrorHand(right, dir / "mirrored", {.axis = 'y', .name = "two_finger_left"});
  const HandCheck check = CheckHand(left.description);
  for (const HandProblem& p : check.problems) ADD_FAILURE() << p.code << ": " << p.message;
  EXPECT_EQ(check.structure.chains.size(), 2u);
  const Deviation d = MirrorDeviation(Compile(Prepared(right)).get(), Compile(Prepared(left.embodiment)).get(), 1);
  EXPECT_LT(d.position, 1e-6);
  EXPECT_LT(d.rotation, 1e-6);
}

// A right hand and its mirror image share every name; prefixed, both fit in
// one model (a bimanual scene), each moving exactly as it did alone: every
// body of the prefixed copy at the original's pose for the same joint
// angles. Shadow has default classes, a main default and meshes named by
// their files; the every-attribute model sets a joint axis in its main
// default, which its mirror image sets the other way.
TEST(HandMirror, PrefixedHandsMergeIntoOneModel) {
  for (const char* name : {"every_attribute", "sharpa_right", "shadow_right"}) {
    const std::string right = std::string(name) == "every_attribute" ? kEveryAttribute : Prepared(Hand(name));
    const std::string left = MirrorMjcf(right, 'y', name);
    tinyxml2::XMLDocument both;
    ParseMjcfText(PrefixMjcfNames(right, "r_", name), name, both);
    AppendRootChildren(both, PrefixMjcfNames(left, "l_", name), name);
    const ModelPtr merged = Compile(PrintMjcf(both));
    for (const auto& [prefix, xml] : {std::pair<std::string, std::string>{"r_", right}, {"l_", left}}) {
      const ModelPtr original = Compile(xml);
      ASSERT_EQ(merged->nbody, 2 * original->nbody - 1) << name;
      ASSERT_EQ(merged->nu, 2 * original->nu) << name;
      ASSERT_EQ(merged->nmesh, 2 * original->nmesh) << name;
      DataPtr d0 = MakeData(original.get()), d1 = MakeData(merged.get());
      std::mt19937 rng(4);
      for (int j = 0; j < original->njnt; ++j) {
        const double q = std::uniform_real_distribution<double>(original->jnt_range[2 * j],
                                                                original->jnt_range[2 * j + 1])(rng);
        d0->qpos[original->jnt_qposadr[j]] = q;
        const std::string joint = mj_id2name(original.get(), mjOBJ_JOINT, j);
        d1->qpos[merged->jnt_qposadr[NameToId(merged.get(), mjOBJ_JOINT, prefix + joint)]] = q;
      }
      for (int a = 0; a < original->nu; ++a) {  // the actuators' classes survive the prefix
        const int m = NameToId(merged.get(), mjOBJ_ACTUATOR, prefix + mj_id2name(original.get(), mjOBJ_ACTUATOR, a));
        ASSERT_GE(m, 0);
        EXPECT_EQ(merged->actuator_gainprm[m * mjNGAIN], original->actuator_gainprm[a * mjNGAIN]) << prefix << a;
        EXPECT_EQ(merged->actuator_ctrlrange[2 * m + 1], original->actuator_ctrlrange[2 * a + 1]) << prefix << a;
      }
      mj_kinematics(original.get(), d0.get());
      mj_kinematics(merged.get(), d1.get());
      double worst = 0;
      for (int b = 1; b < original->nbody; ++b) {
        const int m = NameToId(merged.get(), mjOBJ_BODY, prefix + mj_id2name(original.get(), mjOBJ_BODY, b));
        ASSERT_GE(m, 0);
        worst = std::max(worst, (Eigen::Map<const Vec3>(d1->xpos + 3 * m) - Eigen::Map<const Vec3>(d0->xpos + 3 * b)).norm());
      }
      EXPECT_LT(worst, 1e-12) << name << " " << prefix;
      for (int g = 0; g < original->ngeom; ++g) {  // the classes' geom defaults came along
        const char* geom = mj_id2name(original.get(), mjOBJ_GEOM, g);
        if (!geom) continue;
        const int m = NameToId(merged.get(), mjOBJ_GEOM, prefix + geom);
        ASSERT_GE(m, 0) << geom;
        EXPECT_EQ(merged->geom_contype[m], original->geom_contype[g]) << geom;
        EXPECT_EQ(merged->geom_size[3 * m], original->geom_size[3 * g]) << geom;
      }
    }
  }
}

}  // namespace
}  // namespace doasido::retarget
