// The three hands (doasido's Sharpa-like hand, Shadow and Allegro from the
// menagerie) load from their descriptions, compile on MuJoCo 2.2.2 with the
// floating wrist, and step stably holding their position targets.
#include <cmath>

#include <gtest/gtest.h>

#include "core/error.h"
#include "robot/embodiment.h"
#include "tests/test_util.h"

namespace doasido::retarget {
namespace {

using doasido::testing::SharedData;

const char* kFloor = R"(<mujoco><worldbody>
  <geom name="floor" type="plane" size="0 0 0.05" pos="0 0 -0.3"/>
</worldbody></mujoco>)";

struct Case {
  const char* name;
  int finger_dofs;
  int fingertips;
};

class HandTest : public ::testing::TestWithParam<Case> {};

TEST_P(HandTest, CompilesAndSteps) {
  const Case c = GetParam();
  const Embodiment e = FindEmbodiment(c.name, SharedData() / "robots");
  const HandModel hand = BuildHandModel(e, kFloor, SharedData());
  const mjModel* m = hand.model.get();
  ASSERT_EQ(static_cast<int>(hand.finger_qpos.size()), c.finger_dofs);
  ASSERT_EQ(hand.wrist_qpos.size(), 6u);
  EXPECT_EQ(m->nq, c.finger_dofs + 6);
  int tips = 0;
  for (const auto& p : hand.points) tips += p.fingertip;
  EXPECT_EQ(tips, c.fingertips);

  // The canonical mount: at zero wrist angles the fingers point along +z and
  // the palm side faces +x, as in the human keypoints' wrist frame.
  DataPtr d = MakeData(m);
  mj_kinematics(m, d.get());
  Vec3 wrist = Vec3::Zero(), middle_tip = Vec3::Zero(), index_mcp = Vec3::Zero();
  for (const auto& p : hand.points) {
    if (p.keypoint == 0) wrist = PointPosition(m, d.get(), p);
    if (p.keypoint == 12) middle_tip = PointPosition(m, d.get(), p);
    if (p.keypoint == 5) index_mcp = PointPosition(m, d.get(), p);
  }
  EXPECT_GT((middle_tip - wrist).normalized().z(), 0.8) << (middle_tip - wrist).transpose();
  // Index knuckle on the thumb side: +y for a right hand, -y for a left one.
  const double side = e.side == "left" ? -1.0 : 1.0;
  EXPECT_GT(side * (index_mcp - wrist).y(), 0.005);

  // Hold every actuator at its qpos0 target (clamped to ctrlrange) for 1 s.
  for (int a = 0; a < m->nu; ++a) {
    double target = 0;
    if (m->actuator_trntype[a] == mjTRN_JOINT) {
      target = m->qpos0[m->jnt_qposadr[m->actuator_trnid[2 * a]]];
    }
    if (m->actuator_ctrllimited[a]) {
      target = std::clamp(target, m->actuator_ctrlrange[2 * a], m->actuator_ctrlrange[2 * a + 1]);
    }
    d->ctrl[a] = target;
  }
  const Vec3 mount_start(d->qpos[hand.wrist_qpos[0]], d->qpos[hand.wrist_qpos[1]],
                         d->qpos[hand.wrist_qpos[2]]);
  for (int i = 0; i < 200; ++i) mj_step(m, d.get());
  for (int i = 0; i < m->nq; ++i) ASSERT_TRUE(std::isfinite(d->qpos[i])) << i;
  EXPECT_EQ(d->warning[mjWARN_BADQACC].number, 0);
  const Vec3 mount_end(d->qpos[hand.wrist_qpos[0]], d->qpos[hand.wrist_qpos[1]],
                       d->qpos[hand.wrist_qpos[2]]);
  // Gravity sag of the stiff wrist servo is g / omega^2 = 6 mm.
  EXPECT_LT((mount_end - mount_start).norm(), 0.008);
  for (int i = 0; i < m->nv; ++i) EXPECT_LT(std::abs(d->qvel[i]), 0.2) << "dof " << i;
}

INSTANTIATE_TEST_SUITE_P(ThreeHands, HandTest,
                         ::testing::Values(Case{"sharpa_right", 22, 5}, Case{"sharpa_left", 22, 5},
                                           Case{"shadow", 24, 5}, Case{"allegro", 16, 4}),
                         [](const ::testing::TestParamInfo<Case>& p) { return std::string(p.param.name); });

TEST(Embodiment, ErrorsNameTheFileAndField) {
  doasido::testing::TempDir dir;
  doasido::testing::WriteFile(dir / "bad.json",
                              R"({"model": "sharpa_right.xml", "points": [{"keypoint": 25, "site": "x"}]})");
  try {
    LoadEmbodiment(dir / "bad.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_embodiment");
    EXPECT_EQ(e.site().field, "points[0].keypoint");
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos);
  }
  doasido::testing::WriteFile(dir / "nosite.json",
                              R"({"model": "sharpa_right.xml", "points": [{"keypoint": 8, "site": "nope", "fingertip": true}]})");
  EXPECT_THROW(BuildHandModel(LoadEmbodiment(dir / "nosite.json")), Error);
}

}  // namespace
}  // namespace doasido::retarget
