// The surface of a posed MuJoCo model as triangles, for pictures of a hand
// (`doasido hand check`): mesh geoms as compiled, primitives tessellated.
#pragma once

#include <vector>

#include <mujoco/mujoco.h>

#include "core/mesh.h"

namespace doasido::retarget {

// The geoms worth drawing: the visual-only ones (contype = conaffinity = 0)
// when the model has any, else every geom; planes and height fields never.
std::vector<int> DrawnGeoms(const mjModel* m);

// World-frame triangles of `geoms` for the kinematics in `d` (mj_kinematics
// must have run). Spheres, ellipsoids, capsules and cylinders are
// tessellated with `segments` around their axis.
TriMesh GeomsMesh(const mjModel* m, const mjData* d, const std::vector<int>& geoms, int segments = 16);

}  // namespace doasido::retarget
