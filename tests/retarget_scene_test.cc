// Simulation scenes from object meshes: real YCB scans and a concave mug
// rest on the floor for 2 s of simulation with under 1 mm of drift; the
// decomposition keeps the mug's cavity open; the mass matches the volume;
// the base plate touches only the floor.
#include <cmath>

#include <gtest/gtest.h>

#include "core/mesh.h"
#include "eval/mug_mesh.h"
#include "retarget/scene/convex_decomposition.h"
#include "retarget/scene/scene_builder.h"
#include "robot/mj_model.h"
#include "robot/mjcf_compat.h"
#include "tests/test_util.h"

namespace doasido::retarget {
namespace {

using doasido::testing::SharedData;
using doasido::testing::TempDir;

struct Drift {
  double position = 0;  // m
  double angle = 0;     // rad
};

// Steps the scene for `seconds` and reports how far the object moved.
Drift Simulate(const ObjectScene& scene, double seconds) {
  const PreparedMjcf prepared = PrepareMjcf(scene.xml_path);
  ModelPtr m = CompileMjcfText(prepared.xml, scene.xml_path.string());
  DataPtr d = MakeData(m.get());
  const int body = NameToId(m.get(), mjOBJ_BODY, "object");
  mj_forward(m.get(), d.get());
  const Vec3 p0(d->xpos + 3 * body);
  const Quat q0(d->xquat[4 * body], d->xquat[4 * body + 1], d->xquat[4 * body + 2],
                d->xquat[4 * body + 3]);
  const int steps = static_cast<int>(std::lround(seconds / m->opt.timestep));
  for (int i = 0; i < steps; ++i) mj_step(m.get(), d.get());
  const Vec3 p1(d->xpos + 3 * body);
  const Quat q1(d->xquat[4 * body], d->xquat[4 * body + 1], d->xquat[4 * body + 2],
                d->xquat[4 * body + 3]);
  return {(p1 - p0).norm(), RotationAngle(q0, q1)};
}

class YcbScene : public ::testing::TestWithParam<const char*> {};

TEST_P(YcbScene, RestsOnTheFloor) {
  const TriMesh mesh = LoadMesh(SharedData() / "meshes/ycb" / GetParam());
  TempDir dir;
  const ObjectScene scene = BuildObjectScene(mesh, Pose::Identity(), SceneConfig{}, dir.path());
  EXPECT_GE(scene.hull_files.size(), 1u);
  EXPECT_GT(scene.mass, 0.05);
  EXPECT_LT(scene.mass, 3.0);
  // Settling only removes the contact's give and the scan's uneven bottom.
  EXPECT_LT(scene.settle_shift, 0.003);
  EXPECT_LT(scene.settle_angle, 0.05);
  const Drift drift = Simulate(scene, 2.0);
  EXPECT_LT(drift.position, 0.001);
  EXPECT_LT(drift.angle, 0.01);
}

INSTANTIATE_TEST_SUITE_P(Meshes, YcbScene,
                         ::testing::Values("004_sugar_box_textured.obj",
                                           "006_mustard_bottle_textured.obj"));

TEST(MugScene, DecompositionKeepsTheCavityAndTheMugRests) {
  const MugShape shape;
  const TriMesh mug = MakeMug(shape);
  const std::vector<TriMesh> hulls = ConvexDecomposition(mug);
  EXPECT_GT(hulls.size(), 2u);
  // The cavity stays open: of a grid of points filling the cavity (away from
  // its walls by 2 mm), few fall inside any hull; a single convex hull would
  // hold them all.
  auto covered = [&](const Vec3& p) {
    for (const TriMesh& h : hulls) {
      if (InsideHull(h, p)) return true;
    }
    return false;
  };
  const double rc = shape.radius - shape.wall - 0.002;
  int cavity = 0, cavity_covered = 0;
  for (double x = -rc; x <= rc; x += 0.004) {
    for (double y = -rc; y <= rc; y += 0.004) {
      if (x * x + y * y > rc * rc) continue;
      for (double z = shape.bottom + 0.002; z < shape.height - 0.002; z += 0.004) {
        ++cavity;
        cavity_covered += covered(Vec3(x, y, z));
      }
    }
  }
  ASSERT_GT(cavity, 1000);
  EXPECT_LT(cavity_covered, 0.1 * cavity) << cavity_covered << " of " << cavity;
  // The surface is covered once dilated: points 1 mm inside the outer
  // wall all round and 1 mm above the bottom lie in some dilated hull.
  std::vector<TriMesh> dilated;
  for (const TriMesh& h : hulls) dilated.push_back(DilateConvex(h, 0.002));
  auto skin = [&](const Vec3& p) {
    for (const TriMesh& h : dilated) {
      if (InsideHull(h, p)) return true;
    }
    return false;
  };
  EXPECT_TRUE(skin(Vec3(0.01, 0.01, 0.001)));
  for (int k = 0; k < 8; ++k) {
    const double a = 2 * M_PI * k / 8 + 0.1;
    const double r = shape.radius - 0.001;
    EXPECT_TRUE(skin(Vec3(r * std::cos(a), r * std::sin(a), 0.5 * shape.height))) << k;
  }

  TempDir dir;
  SceneConfig config;
  const ObjectScene scene = BuildObjectScene(mug, Pose::Identity(), config, dir.path());
  // Mass = density x volume: a 48-gon lathe of the cup plus a half torus
  // handle (pi^2 a b^2; its ends sunk 0.5 mm into the wall).
  const double lathe = 48 * 0.5 * std::sin(2 * M_PI / 48);  // polygon area / r^2
  const double ri = shape.radius - shape.wall;
  const double volume = lathe * (shape.radius * shape.radius * shape.height -
                                 ri * ri * (shape.height - shape.bottom)) +
                        M_PI * M_PI * shape.handle_radius * shape.handle_tube * shape.handle_tube;
  EXPECT_FALSE(scene.inertia_from_hulls);
  EXPECT_NEAR(scene.mass, config.density * volume, 0.01 * config.density * volume);
  const Drift drift = Simulate(scene, 2.0);
  EXPECT_LT(drift.position, 0.001);
  EXPECT_LT(drift.angle, 0.01);
}

TEST(MugScene, BasePlateHoldsATiltedMugAndTouchesOnlyTheFloor) {
  const TriMesh mug = MakeMug();
  const Pose tilted{Quat(Eigen::AngleAxisd(0.35, Vec3::UnitX())), Vec3::Zero()};
  TempDir with_dir, without_dir;
  SceneConfig config;
  config.base_plate = true;
  const ObjectScene with_plate = BuildObjectScene(mug, tilted, config, with_dir.path());
  EXPECT_LT(with_plate.settle_angle, 0.01);  // stays tilted while settling
  const Drift held = Simulate(with_plate, 2.0);
  EXPECT_LT(held.position, 0.001);
  EXPECT_LT(held.angle, 0.01);
  // Without the plate the tilted mug falls back onto its base while settling.
  config.base_plate = false;
  const ObjectScene without = BuildObjectScene(mug, tilted, config, without_dir.path());
  EXPECT_GT(without.settle_angle, 0.2);

  ModelPtr m = CompileMjcfText(PrepareMjcf(with_plate.xml_path).xml, "scene");
  const int plate = NameToId(m.get(), mjOBJ_GEOM, "object_base_plate");
  const int floor = NameToId(m.get(), mjOBJ_GEOM, "floor");
  ASSERT_GE(plate, 0);
  auto collide = [&](int t1, int a1, int t2, int a2) { return (t1 & a2) || (t2 & a1); };
  EXPECT_TRUE(collide(m->geom_contype[plate], m->geom_conaffinity[plate], m->geom_contype[floor],
                      m->geom_conaffinity[floor]));
  // A hand geom keeps MuJoCo's default bits (1, 1).
  EXPECT_FALSE(collide(m->geom_contype[plate], m->geom_conaffinity[plate], 1, 1));
}

TEST(MassProperties, UnitCubeMatchesClosedForm) {
  TriMesh cube;
  cube.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) cube.vertices.row(i) << (i & 1), (i >> 1 & 1), (i >> 2 & 1);
  cube.faces.resize(12, 3);
  cube.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2,
      4, 6, 1, 3, 5, 3, 7, 5;
  const MassProperties mp = ComputeMassProperties(cube);
  EXPECT_NEAR(mp.volume, 1.0, 1e-12);
  EXPECT_TRUE(mp.com.isApprox(Vec3(0.5, 0.5, 0.5), 1e-12));
  EXPECT_TRUE(mp.inertia.isApprox(Mat3::Identity() / 6.0, 1e-12));
  // Dilating the cube by 2 mm moves each face out by exactly 2 mm.
  const TriMesh grown = DilateConvex(cube, 0.002);
  EXPECT_TRUE(grown.Min().isApprox(Vec3::Constant(-0.002), 1e-12));
  EXPECT_TRUE(grown.Max().isApprox(Vec3::Constant(1.002), 1e-12));
}

// A box built with its own copy of each corner per face (as renderers want
// for flat shading) is closed once welded: one hull, and the mass of its
// volume rather than of a hollow shell of slabs.
TEST(MassProperties, AnUnweldedBoxIsWeldedIntoOneSolidHull) {
  TriMesh cube;
  cube.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) cube.vertices.row(i) << 0.05 * (i & 1), 0.04 * (i >> 1 & 1), 0.08 * (i >> 2 & 1);
  cube.faces.resize(12, 3);
  cube.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2,
      4, 6, 1, 3, 5, 3, 7, 5;
  TriMesh unwelded;
  unwelded.vertices.resize(36, 3);
  unwelded.faces.resize(12, 3);
  for (int f = 0; f < 12; ++f) {
    for (int k = 0; k < 3; ++k) {
      unwelded.vertices.row(3 * f + k) = cube.vertices.row(cube.faces(f, k));
      unwelded.faces(f, k) = 3 * f + k;
    }
  }
  ASSERT_FALSE(IsClosed(unwelded));
  const TriMesh welded = WeldVertices(unwelded);
  EXPECT_EQ(welded.num_vertices(), 8);
  EXPECT_EQ(welded.num_faces(), 12);
  EXPECT_TRUE(IsClosed(welded));
  TempDir dir;
  SceneConfig config;
  config.settle_seconds = 0;
  const ObjectScene scene = BuildObjectScene(unwelded, Pose{}, config, dir.path());
  EXPECT_EQ(scene.hull_files.size(), 1u);
  EXPECT_FALSE(scene.inertia_from_hulls);
  EXPECT_NEAR(scene.mass, 1000 * 0.05 * 0.04 * 0.08, 1e-9);
}

}  // namespace
}  // namespace doasido::retarget
