// The object's shape for the bundle: a closed, outward-facing mesh of the
// lifted box's extents in the box's own frame (centre at the origin, x to
// the right face, y to the top, z to the front; metres): a capped cylinder
// along y for round objects (cups and mugs: diameter size.x, height size.y),
// else the box.
#pragma once

#include "core/geometry.h"
#include "core/mesh.h"

namespace doasido::objects {

TriMesh ObjectMesh(const Vec3& size, bool cylinder, int segments = 48);

}  // namespace doasido::objects
