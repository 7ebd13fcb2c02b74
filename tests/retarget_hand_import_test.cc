// Bring your own hand: the generated description of the three shipped hands
// finds the hand-written fingertips, knuckles and thumb; a URDF written here
// imports, retargets the real human keypoints, and its faults are refused
// with the file and the next step; the checker names problems.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <regex>

#include <gtest/gtest.h>

#include "core/error.h"
#include "retarget/kinematic/kinematic_retarget.h"
#include "robot/embodiment.h"
#include "robot/hand_check.h"
#include "robot/hand_description.h"
#include "robot/mjcf_compat.h"
#include "robot/urdf_import.h"
#include "tests/test_util.h"
#include "tests/two_finger_hand.h"

namespace doasido::retarget {
namespace {

using doasido::testing::SharedData;
using doasido::testing::TempDir;
using doasido::testing::TwoFingerHandOptions;
using doasido::testing::WriteTwoFingerHand;

ModelPtr RawModel(const Embodiment& e) {
  return CompileMjcfText(PrepareMjcf(e.model_path).xml, e.model_path.string());
}

std::string BodyName(const mjModel* m, int b) { return b < 0 ? "?" : mj_id2name(m, mjOBJ_BODY, b); }

// keypoint -> body name of the description's points with that keypoint.
std::map<int, std::string> BodiesByKeypoint(const mjModel* m, const Embodiment& e) {
  std::map<int, std::string> out;
  for (const EmbodimentPoint& p : e.points) out[p.keypoint] = BodyName(m, PointBody(m, p));
  return out;
}

class ShippedHand : public ::testing::TestWithParam<const char*> {};

TEST_P(ShippedHand, GeneratedDescriptionFindsTheHandWrittenTipsKnucklesAndThumb) {
  const Embodiment written = FindEmbodiment(GetParam(), SharedData() / "robots");
  ModelPtr model = RawModel(written);
  const mjModel* m = model.get();
  const HandStructure s = AnalyzeHand(m, written.model_path.string());
  const HandDescription generated = DescribeHand(m, s, "gen", written.side, written.model_path.string());
  const auto want = BodiesByKeypoint(m, written);
  const auto got = BodiesByKeypoint(m, generated.embodiment);
  int tips = 0;
  for (const EmbodimentPoint& p : written.points) {
    if (!p.fingertip) continue;
    ++tips;
    ASSERT_TRUE(got.count(p.keypoint)) << "no generated point for fingertip keypoint " << p.keypoint;
    EXPECT_EQ(got.at(p.keypoint), want.at(p.keypoint)) << "fingertip keypoint " << p.keypoint;
  }
  EXPECT_EQ(tips, static_cast<int>(s.chains.size()));
  for (int knuckle : {5, 9, 13, 17}) {
    if (want.count(knuckle)) {
      EXPECT_EQ(got.at(knuckle), want.at(knuckle)) << "knuckle " << knuckle;
    }
  }
  // The generated wrist and fingertip points sit near the hand-written ones.
  DataPtr d = MakeData(m);
  mj_kinematics(m, d.get());
  auto where = [&](const Embodiment& e, int keypoint) {
    for (const EmbodimentPoint& p : e.points) {
      if (p.keypoint != keypoint) continue;
      const bool site = !p.site.empty();
      const int id = site ? mj_name2id(m, mjOBJ_SITE, p.site.c_str()) : mj_name2id(m, mjOBJ_BODY, p.body.c_str());
      ModelPoint mp;
      (site ? mp.site : mp.body) = id;
      mp.offset = Vec3(p.pos[0], p.pos[1], p.pos[2]);
      return PointPosition(m, d.get(), mp);
    }
    return Vec3(Vec3::Constant(1e9));
  };
  for (int k : {0, 4, 8, 12, 16, 20}) {
    if (!want.count(k)) continue;
    const double gap = (where(generated.embodiment, k) - where(written, k)).norm();
    std::printf("  %s keypoint %d: generated %.1f mm from hand-written\n", GetParam(), k, 1000 * gap);
    EXPECT_LT(gap, 0.015) << "keypoint " << k;
  }
  // The thumb: the hand-written thumb tip lies on the chain found to oppose the others.
  const HandChain& thumb = s.chains.front();
  EXPECT_EQ(thumb.finger, "thumb");
  EXPECT_EQ(BodyName(m, thumb.tip_body), want.at(4));
  for (const std::string& note : s.notes) std::printf("  %s: %s\n", GetParam(), note.c_str());
}

INSTANTIATE_TEST_SUITE_P(Hands, ShippedHand, ::testing::Values("sharpa_right", "sharpa_left", "shadow", "allegro"));

std::vector<Keypoints21> HumanFrames(size_t count) {
  auto frames = ReadKeypointCsv(SharedData() / "retarget/human_hand_keypoints_right.csv");
  frames.resize(std::min(count, frames.size()));
  return frames;
}

TEST(UrdfImport, TwoFingerHandImportsAndRetargetsRealKeypoints) {
  TempDir dir;
  const auto urdf = WriteTwoFingerHand(dir.path() / "src");
  const ImportedHand imported = ImportUrdf(urdf, dir / "out");
  ASSERT_TRUE(std::filesystem::exists(dir / "out/two_finger.xml"));
  ASSERT_TRUE(std::filesystem::exists(dir / "out/meshes/palm.obj")) << "PLY converted to OBJ";
  ASSERT_EQ(imported.structure.chains.size(), 2u);

  // The description reads back through the ordinary loader and names the tips.
  const Embodiment e = LoadEmbodiment(imported.description);
  std::map<int, std::string> tips;
  for (const EmbodimentPoint& p : e.points) {
    if (p.fingertip) tips[p.keypoint] = p.body;
  }
  EXPECT_EQ(tips, (std::map<int, std::string>{{4, "thumb_tip"}, {8, "index_tip"}}));

  // Position actuators on every finger joint, control range = joint range.
  const HandModel hand = BuildHandModel(e);
  const mjModel* m = hand.model.get();
  int finger_actuators = 0;
  for (int a = 0; a < m->nu; ++a) {
    const int j = m->actuator_trnid[2 * a];
    const std::string name = mj_id2name(m, mjOBJ_JOINT, j);
    if (name.rfind("doasido_wrist", 0) == 0) continue;
    ++finger_actuators;
    EXPECT_GT(m->actuator_gainprm[a * mjNGAIN], 0) << name;
    EXPECT_DOUBLE_EQ(m->actuator_ctrlrange[2 * a], m->jnt_range[2 * j]) << name;
    EXPECT_DOUBLE_EQ(m->actuator_ctrlrange[2 * a + 1], m->jnt_range[2 * j + 1]) << name;
  }
  EXPECT_EQ(finger_actuators, 7);
  EXPECT_EQ(hand.wrist_qpos.size(), 6u) << "floating wrist added";

  // Real human keypoints: the thumb and index tips are reached.
  KinematicConfig config;
  config.restarts = 2;
  KinematicRetargeter solver(hand, config);
  const auto frames = HumanFrames(5);
  const HandTrajectory t = solver.Solve(frames, {}, 30);
  ASSERT_EQ(t.fingertip_error.size(), frames.size());
  double mean = 0;
  for (double x : t.fingertip_error) mean += x / frames.size();
  std::printf("  two-finger URDF hand: scale %.3f, fingertip error mean %.1f mm\n", t.scale, 1000 * mean);
  EXPECT_LT(mean, 0.012);
}

// Code, file, the offending element and the import command to rerun.
void ExpectRefusal(const std::function<void()>& f, const std::string& code, const std::string& file,
                   const std::string& mentions, const std::string& next_step) {
  try {
    f();
    ADD_FAILURE() << "no error; expected " << code;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_EQ(e.site().file, file) << e.what();
    EXPECT_NE(std::string(e.what()).find(mentions), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(next_step), std::string::npos) << e.what();
  }
}

// Inputs that crash MuJoCo 2.2.2's own URDF reader (found by
// hand_import_fuzz) are refused before it sees them.
TEST(UrdfImport, AnUnknownJointTypeOrAJointWithoutLinksIsRefusedBeforeMujoco) {
  TempDir dir;
  auto urdf = WriteTwoFingerHand(dir / "typo");
  std::string text = doasido::testing::ReadFile(urdf);
  text.replace(text.find("type=\"revolute\""), 15, "type=\"revolu?e\"");
  doasido::testing::WriteFile(urdf, text);
  ExpectRefusal([&] { ImportUrdf(urdf, dir / "out1"); }, kBadUrdfError, urdf.string(),
                "thumb_cmc_fe", "type 'revolu?e'");
  urdf = WriteTwoFingerHand(dir / "orphan");
  text = doasido::testing::ReadFile(urdf);
  text.replace(text.find("<parent link=\"palm\"/>"), 20, "");
  doasido::testing::WriteFile(urdf, text);
  ExpectRefusal([&] { ImportUrdf(urdf, dir / "out2"); }, kBadUrdfError, urdf.string(),
                "thumb_cmc_fe", "<parent link=");
}

TEST(UrdfImport, MissingMeshUnlimitedJointAndWrongRootAreNamed) {
  TempDir dir;
  TwoFingerHandOptions missing;
  missing.palm_mesh = "meshes/palm_v2.stl";
  auto urdf = WriteTwoFingerHand(dir / "missing", missing);
  ExpectRefusal([&] { ImportUrdf(urdf, dir / "out1"); }, kMissingMeshError, urdf.string(),
                "meshes/palm_v2.stl", "doasido hand import --urdf " + urdf.string());

  TwoFingerHandOptions unlimited;
  unlimited.index_dip_continuous = true;
  urdf = WriteTwoFingerHand(dir / "unlimited", unlimited);
  ExpectRefusal([&] { ImportUrdf(urdf, dir / "out2"); }, kUnlimitedJointError, urdf.string(),
                "index_dip", "<limit lower=");

  TwoFingerHandOptions sdf;
  sdf.root = "sdf";
  urdf = WriteTwoFingerHand(dir / "sdf", sdf);
  ExpectRefusal([&] { ImportUrdf(urdf, dir / "out3"); }, kWrongRootError, urdf.string(), "<sdf>",
                "doasido hand import --urdf");

  const auto mjcf = SharedData() / "robots/wonik_allegro/right_hand.xml";
  ExpectRefusal([&] { ImportUrdf(mjcf, dir / "out4"); }, kWrongRootError, mjcf.string(), "<mujoco>",
                "doasido hand import --mjcf");
}

TEST(UrdfImport, MimicCouplingIsReportedAsDropped) {
  TempDir dir;
  TwoFingerHandOptions mimic;
  mimic.index_dip_mimics_pip = true;
  EXPECT_TRUE(ImportUrdf(WriteTwoFingerHand(dir / "plain"), dir / "out1").warnings.empty());
  const ImportedHand h = ImportUrdf(WriteTwoFingerHand(dir / "mimic", mimic), dir / "out2");
  ASSERT_EQ(h.warnings.size(), 1u);
  EXPECT_NE(h.warnings[0].find("'index_dip' mimics 'index_pip'"), std::string::npos) << h.warnings[0];
}

TEST(UrdfImport, UrdfWhereAHandIsExpectedAnswersWithTheImportCommand) {
  TempDir dir;
  const auto urdf = WriteTwoFingerHand(dir.path());
  const std::string command = "doasido hand import --urdf " + urdf.string();
  ExpectRefusal([&] { FindEmbodiment(urdf.string(), {}); }, "bad_embodiment", urdf.string(), "URDF", command);
  doasido::testing::WriteFile(dir / "desc.json",
                              R"({"model": "two_finger.urdf", "points": [{"keypoint": 8, "body": "index_tip", "fingertip": true}]})");
  ExpectRefusal([&] { LoadEmbodiment(dir / "desc.json"); }, "bad_embodiment", (dir / "desc.json").string(),
                "URDF", command);
  ExpectRefusal([&] { PrepareMjcf(urdf); }, "bad_mjcf", urdf.string(), "<robot>", command);
}

// A URDF converted by MuJoCo with its default fusestatic="true" (as a user
// adding <mujoco><compiler/></mujoco> by hand would) loses the palm and the
// tip links; the description's refusal names the body and the option.
TEST(UrdfImport, FusedAwayBodyNamesTheBodyAndTheCompilerOption) {
  TempDir dir;
  const ImportedHand imported = ImportUrdf(WriteTwoFingerHand(dir / "src"), dir / "out");
  std::string urdf = doasido::testing::ReadFile(dir / "out/two_finger.urdf");
  urdf = std::regex_replace(urdf, std::regex("fusestatic=\"false\""), "fusestatic=\"true\"");
  doasido::testing::WriteFile(dir / "out/fused.urdf", urdf);
  char error[1000] = "";
  mjModel* m = mj_loadXML((dir / "out/fused.urdf").c_str(), nullptr, error, sizeof(error));
  ASSERT_TRUE(m) << error;
  ASSERT_TRUE(mj_saveLastXML((dir / "out/fused.xml").c_str(), m, error, sizeof(error))) << error;
  EXPECT_EQ(mj_name2id(m, mjOBJ_BODY, "index_tip"), -1) << "fused away";
  mj_deleteModel(m);
  std::string json = doasido::testing::ReadFile(imported.description);
  json = std::regex_replace(json, std::regex("two_finger\\.xml"), "fused.xml");
  doasido::testing::WriteFile(dir / "out/fused.json", json);
  try {
    BuildHandModel(LoadEmbodiment(dir / "out/fused.json"));
    ADD_FAILURE() << "fused model accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.site().file, (dir / "out/fused.xml").string());
    EXPECT_NE(std::string(e.what()).find("model has no body '"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fusestatic=\"false\""), std::string::npos) << e.what();
  }
}

TEST(HandCheck, ImportedHandIsCleanAndBrokenOnesAreNamed) {
  TempDir dir;
  const ImportedHand imported = ImportUrdf(WriteTwoFingerHand(dir / "src"), dir / "out");
  {
    const HandCheck c = CheckHand(imported.description);
    EXPECT_TRUE(c.problems.empty()) << c.problems.front().message;
    EXPECT_EQ(c.structure.chains.size(), 2u);
    EXPECT_EQ(c.joints.size(), 7u);
  }
  std::string xml = doasido::testing::ReadFile(imported.mjcf);
  // index_pip loses its range; index_dip's actuator reaches beyond its joint.
  xml = std::regex_replace(xml, std::regex("(<joint name=\"index_pip\"[^>]*?) range=\"[^\"]*\""), "$1");
  xml = std::regex_replace(xml, std::regex("(<position name=\"index_dip\"[^>]*?)ctrlrange=\"[^\"]*\""),
                           "$1ctrlrange=\"0 2.5\"");
  doasido::testing::WriteFile(imported.mjcf, xml);
  std::string json = doasido::testing::ReadFile(imported.description);
  json = std::regex_replace(json, std::regex("\"index_tip\""), "\"index_nail\"");
  doasido::testing::WriteFile(imported.description, json);
  const HandCheck c = CheckHand(imported.description);
  std::map<std::string, std::string> found;
  for (const HandProblem& p : c.problems) found[p.code] += p.message + " | ";
  ASSERT_TRUE(found.count(kUnlimitedJointProblem));
  EXPECT_NE(found[kUnlimitedJointProblem].find("index_pip"), std::string::npos);
  ASSERT_TRUE(found.count(kActuatorRangeProblem));
  EXPECT_NE(found[kActuatorRangeProblem].find("index_dip"), std::string::npos);
  ASSERT_TRUE(found.count(kMissingBodyProblem));
  EXPECT_NE(found[kMissingBodyProblem].find("index_nail"), std::string::npos);
}

TEST(HandCheck, FlexedPoseCurlsEveryFingerTowardThePalm) {
  const Embodiment e = FindEmbodiment("sharpa_right", {});
  ModelPtr model = RawModel(e);
  const mjModel* m = model.get();
  const HandStructure s = AnalyzeHand(m, "sharpa");
  const Eigen::VectorXd q = FlexedPose(m, s, 1.0);
  // Sharpa's flexion joints are the *_fe, pip, dip and ip ones: all at their upper limit.
  for (const HandChain& c : s.chains) {
    for (int j : c.flexion) EXPECT_DOUBLE_EQ(q[m->jnt_qposadr[j]], m->jnt_range[2 * j + 1]);
  }
  EXPECT_EQ(s.chains[1].flexion.size(), 3u) << "index: MCP FE, PIP, DIP";
}

}  // namespace
}  // namespace doasido::retarget
