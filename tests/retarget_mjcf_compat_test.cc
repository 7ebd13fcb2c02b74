// The compatibility pass: a model written for MuJoCo >= 3 (dampratio,
// inheritrange, implicitfast, ranges without limited flags) is refused by
// 2.2.2 as written and loads after the pass, with every rewrite reported and
// the rewritten values equal to their definitions.
#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "robot/mj_model.h"
#include "robot/mjcf_compat.h"
#include "tests/test_util.h"

namespace doasido::retarget {
namespace {

using doasido::testing::TempDir;
using doasido::testing::WriteFile;

const char* kMain = R"(<mujoco model="compat">
  <compiler angle="radian"/>
  <option timestep="0.005" integrator="implicitfast"/>
  <default>
    <default class="finger">
      <joint range="-1 1" damping="0.1"/>
      <position kp="2" dampratio="1" inheritrange="0.5"/>
    </default>
  </default>
  <worldbody>
    <body name="link" pos="0 0 0.1">
      <joint name="hinge" class="finger" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01" mass="0.1"/>
    </body>
    <body name="slider" pos="0 0.2 0.1">
      <joint name="slide" type="slide" axis="1 0 0" range="-0.1 0.1"/>
      <geom type="box" size="0.02 0.02 0.02" mass="0.5"/>
    </body>
  </worldbody>
  <include file="actuators.xml"/>
</mujoco>
)";

const char* kActuators = R"(<mujoco>
  <actuator>
    <position name="a_hinge" joint="hinge" class="finger"/>
    <position name="a_slide" joint="slide" kp="50" dampratio="0.7" ctrlrange="-0.1 0.1"/>
  </actuator>
</mujoco>
)";

// kMain with the include replaced by the actuator block.
std::string SingleFile() {
  std::string main = kMain;
  const std::string act = kActuators;
  const size_t pos = main.find("<include");
  const size_t end = main.find("/>", pos) + 2;
  const size_t a = act.find("<actuator>");
  const size_t b = act.find("</actuator>") + std::string("</actuator>").size();
  return main.replace(pos, end - pos, act.substr(a, b - a));
}

int Count(const std::vector<CompatChange>& changes, const std::string& attribute) {
  int n = 0;
  for (const auto& c : changes) n += c.attribute == attribute;
  return n;
}

TEST(MjcfCompat, RewritesNewerAttributesSoMuJoCo222Loads) {
  TempDir dir;
  WriteFile(dir / "model.xml", kMain);
  WriteFile(dir / "actuators.xml", kActuators);

  // As written (includes pasted in), 2.2.2 refuses the model.
  EXPECT_THROW(CompileMjcfText(SingleFile(), "raw"), Error);

  const PreparedMjcf prepared = PrepareMjcf(dir / "model.xml");
  ModelPtr m = CompileMjcfText(prepared.xml, "prepared");
  ASSERT_TRUE(m);

  const auto& ch = prepared.changes;
  EXPECT_EQ(Count(ch, "integrator"), 1);
  EXPECT_EQ(Count(ch, "limited"), 2);      // default joint range and the slide
  EXPECT_EQ(Count(ch, "ctrllimited"), 1);  // a_slide
  EXPECT_EQ(Count(ch, "inheritrange"), 1);
  EXPECT_EQ(Count(ch, "dampratio"), 2);
  for (const auto& c : ch) {
    // Each rewrite names the file the attribute was written in: a_slide's
    // dampratio is in the included file, a_hinge's comes from a default
    // class in the main file.
    if (c.attribute == "dampratio" && c.element.find("a_slide") != std::string::npos) {
      EXPECT_THAT(c.file, ::testing::EndsWith("actuators.xml"));
    }
    if (c.attribute == "dampratio" && c.element.find("a_hinge") != std::string::npos) {
      EXPECT_THAT(c.file, ::testing::EndsWith("model.xml"));
      EXPECT_THAT(c.element, ::testing::HasSubstr("default class=finger"));
    }
    if (c.attribute == "integrator") {
      EXPECT_EQ(c.old_value, "implicitfast");
      EXPECT_EQ(c.new_value, "implicit");
      EXPECT_THAT(c.file, ::testing::EndsWith("model.xml"));
    }
  }
  EXPECT_EQ(m->opt.integrator, mjINT_IMPLICIT);

  // inheritrange 0.5 of [-1, 1] about its middle.
  const int a_hinge = NameToId(m.get(), mjOBJ_ACTUATOR, "a_hinge");
  EXPECT_TRUE(m->actuator_ctrllimited[a_hinge]);
  EXPECT_NEAR(m->actuator_ctrlrange[2 * a_hinge], -0.5, 1e-9);
  EXPECT_NEAR(m->actuator_ctrlrange[2 * a_hinge + 1], 0.5, 1e-9);

  // dampratio z -> joint damping += 2 z sqrt(kp M0).
  const int slide = m->jnt_dofadr[NameToId(m.get(), mjOBJ_JOINT, "slide")];
  EXPECT_NEAR(m->dof_M0[slide], 0.5, 1e-9);  // the box's mass
  EXPECT_NEAR(m->dof_damping[slide], 2 * 0.7 * std::sqrt(50 * 0.5), 1e-6);
  const int hinge = m->jnt_dofadr[NameToId(m.get(), mjOBJ_JOINT, "hinge")];
  EXPECT_NEAR(m->dof_damping[hinge], 0.1 + 2 * 1.0 * std::sqrt(2 * m->dof_M0[hinge]), 1e-6);

  // The converted damping gives the servo the damping ratio asked for: a
  // step response of the slide (z = 0.7) overshoots by exp(-pi z / sqrt(1 - z^2))
  // = 4.6%.
  DataPtr d = MakeData(m.get());
  const int a_slide = NameToId(m.get(), mjOBJ_ACTUATOR, "a_slide");
  d->ctrl[a_slide] = 0.05;
  double peak = 0;
  const int qslide = m->jnt_qposadr[NameToId(m.get(), mjOBJ_JOINT, "slide")];
  for (int i = 0; i < 400; ++i) {
    mj_step(m.get(), d.get());
    peak = std::max(peak, d->qpos[qslide]);
  }
  EXPECT_NEAR(d->qpos[qslide], 0.05, 1e-3);
  EXPECT_NEAR(peak / 0.05 - 1, std::exp(-M_PI * 0.7 / std::sqrt(1 - 0.49)), 0.01);
}

TEST(MjcfCompat, RefusesPlyMeshesWithTheFileNamed) {
  TempDir dir;
  WriteFile(dir / "model.xml", R"(<mujoco><asset><mesh file="part.ply"/></asset></mujoco>)");
  try {
    PrepareMjcf(dir / "model.xml");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_mjcf");
    EXPECT_THAT(e.what(), ::testing::HasSubstr("model.xml"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("PLY"));
  }
}

TEST(MjcfCompat, LeavesA222ModelUnchanged) {
  TempDir dir;
  WriteFile(dir / "model.xml", R"(<mujoco><worldbody><body><joint limited="true" range="0 1"/>
    <geom size="0.1"/></body></worldbody></mujoco>)");
  EXPECT_TRUE(PrepareMjcf(dir / "model.xml").changes.empty());
}

}  // namespace
}  // namespace doasido::retarget
