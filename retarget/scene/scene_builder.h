// Simulation scenes for retargeting (seed appendix "Retargeting" and
// "Object Base"): an object mesh becomes a free-floating MuJoCo body made of
// dilated convex pieces, resting on a floor, written as MJCF plus OBJ hull
// files into a folder (MuJoCo 2.2.2 reads OBJ and STL, not PLY).
//
// Contact model (documented defaults, SceneConfig):
//  - timestep 5 ms (seed), implicit integrator, elliptic friction cones with
//    impratio 10 (hard, non-slipping frictional contacts, as in the menagerie
//    hand scenes);
//  - object hulls: condim 4 (sliding plus torsional friction, so a pinch
//    grasp does not spin the object), friction 1 / 0.005 / 0.0001,
//    solref (0.01 s, damping ratio 1) = twice the timestep, the stiffest
//    MuJoCo allows stably, solimp (0.95, 0.99, 1 mm) so resting penetration
//    stays well under a millimetre;
//  - collision bits: floor contype=conaffinity=3, object hulls 1 (touch the
//    floor and the hand, whose geoms keep MuJoCo's default 1), base plate 2
//    (touches only the floor: 2&1 = 0 with the hand).
// Mass and inertia come from the mesh volume times `density` (Eberly's
// polyhedral integrals of the original mesh when it is closed; otherwise
// of the undilated hulls), written as an explicit <inertial>, so the 2 mm
// skin and overlapping hulls do not add mass.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/geometry.h"
#include "core/mesh.h"
#include "retarget/scene/convex_decomposition.h"

namespace doasido::retarget {

struct SceneConfig {
  double density = 1000;          // kg/m^3 (water; hollow household objects are lighter)
  double dilation = 0.002;        // m, outward offset of every hull (seed: 2 mm)
  bool base_plate = false;        // seed "Object Base": a plate touching only the floor
  double plate_thickness = 0.002; // m
  bool place_on_floor = true;     // shift the pose vertically so the object rests on z = 0
  double settle_seconds = 0.5;    // then simulate this long and start from the settled pose
  double timestep = 0.005;        // s (seed sim_dt)
  std::array<double, 3> friction{1.0, 0.005, 0.0001};
  std::array<double, 2> solref{0.01, 1.0};
  std::array<double, 3> solimp{0.95, 0.99, 0.001};
  int condim = 4;
  DecompositionConfig decomposition;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(SceneConfig, density, dilation, base_plate,
                                                plate_thickness, place_on_floor, settle_seconds, timestep, friction,
                                                solref, solimp, condim, decomposition)

struct ObjectScene {
  std::filesystem::path xml_path;       // <out_dir>/scene.xml: floor + object, loads on its own
  std::vector<std::string> hull_files;  // relative to out_dir
  Pose pose;                            // object -> world, after placement and settling
  double settle_shift = 0;              // m the object moved while settling
  double settle_angle = 0;              // rad it turned while settling
  double mass = 0;                      // kg
  Vec3 com = Vec3::Zero();              // object frame
  Mat3 inertia = Mat3::Zero();          // about com, object axes
  double volume = 0;                    // m^3 used for the mass
  bool inertia_from_hulls = false;      // the mesh was not closed
};

// Decomposes, dilates and writes `mesh` (object frame, metres) as the body
// "object" (free joint "object_free") at `pose` above a floor plane "floor"
// at z = 0; files go to `out_dir` (created). With place_on_floor the object
// is lowered onto the floor and left to settle for settle_seconds (a scanned
// bottom is never flat; contacts are soft), and the settled pose is written,
// so the scene starts at rest. Throws Error("bad_mesh") or
// Error("io") naming the file.
ObjectScene BuildObjectScene(const TriMesh& mesh, const Pose& pose, const SceneConfig& config,
                             const std::filesystem::path& out_dir);

}  // namespace doasido::retarget
