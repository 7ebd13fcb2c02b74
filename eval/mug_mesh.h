// A concave test object: a mug (a lathed cup with a half-torus handle), the
// shape that convex decomposition must not fill in. Closed, outward faces,
// metres, bottom centre at the origin, axis +z, handle on +x.
#pragma once

#include "core/mesh.h"

namespace doasido::retarget {

struct MugShape {
  double radius = 0.04;          // outer
  double height = 0.095;
  double wall = 0.006;
  double bottom = 0.008;         // base thickness
  double handle_radius = 0.03;   // half-torus major radius
  double handle_tube = 0.005;    // minor radius
  int segments = 48;
};

TriMesh MakeMug(const MugShape& shape = {});

}  // namespace doasido::retarget
