#include "objects/object_shape.h"

#include <cmath>

#include "core/mesh_builder.h"

namespace doasido::objects {
namespace {

TriMesh Box(const Vec3& size) {
  MeshBuilder m;
  for (int i = 0; i < 8; ++i) {  // bit 2: x, bit 1: y, bit 0: z (objects/box_keypoints.h)
    m.Add(Vec3((i & 4) ? 1 : -1, (i & 2) ? 1 : -1, (i & 1) ? 1 : -1).cwiseProduct(size) / 2);
  }
  // Each face counter-clockwise seen from outside.
  m.Quad(4, 6, 7, 5);  // +x
  m.Quad(0, 1, 3, 2);  // -x
  m.Quad(2, 3, 7, 6);  // +y
  m.Quad(0, 4, 5, 1);  // -y
  m.Quad(1, 5, 7, 3);  // +z
  m.Quad(0, 2, 6, 4);  // -z
  return m.Mesh();
}

TriMesh Cylinder(double radius, double height, int segments) {
  MeshBuilder m;
  const int top = m.Add(Vec3(0, height / 2, 0)), bottom = m.Add(Vec3(0, -height / 2, 0));
  const int first = static_cast<int>(m.vertices.size());
  for (int i = 0; i < segments; ++i) {
    const double a = 2 * M_PI * i / segments;
    // Seen from +y, angle a runs from +z toward +x: clockwise about +y.
    const Vec3 rim(radius * std::sin(a), 0, radius * std::cos(a));
    m.Add(rim + Vec3(0, height / 2, 0));
    m.Add(rim - Vec3(0, height / 2, 0));
  }
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    const int ut = first + 2 * i, ub = ut + 1, vt = first + 2 * j, vb = vt + 1;
    m.Tri(top, ut, vt);
    m.Tri(bottom, vb, ub);
    m.Quad(ub, vb, vt, ut);
  }
  return m.Mesh();
}

}  // namespace

TriMesh ObjectMesh(const Vec3& size, bool cylinder, int segments) {
  return cylinder ? Cylinder(size.x() / 2, size.y(), segments) : Box(size);
}

}  // namespace doasido::objects
