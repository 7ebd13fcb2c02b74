#include "robot/hand_mesh.h"

#include <cmath>

namespace doasido::retarget {
namespace {

using Rows = std::vector<Eigen::Vector3d>;
using Tris = std::vector<Eigen::Vector3i>;

// A closed surface of revolution about z: `rings` latitude rings (none on
// the equator), each point scaled by `radius` and shifted by +-`half` along
// z on its hemisphere. Gives spheres (half 0), capsules, and with flat = true
// (rings pushed to the rims) cylinders.
void Revolution(double rx, double ry, double rz, double half, bool flat, int segments, Rows& v, Tris& f) {
  const int rings = segments / 2 + 1;  // odd count of interior steps: no equator ring
  const int base = static_cast<int>(v.size());
  v.emplace_back(0, 0, rz + half);
  for (int i = 1; i <= rings; ++i) {
    const double theta = M_PI * i / (rings + 1);
    double z = std::cos(theta), r = std::sin(theta);
    if (flat) {
      z = z > 0 ? 1 : -1;
      r = 1;
    }
    for (int k = 0; k < segments; ++k) {
      const double phi = 2 * M_PI * k / segments;
      v.emplace_back(rx * r * std::cos(phi), ry * r * std::sin(phi), rz * z + (z > 0 ? half : -half));
    }
  }
  v.emplace_back(0, 0, -rz - half);
  const int bottom = static_cast<int>(v.size()) - 1;
  auto at = [&](int ring, int k) { return base + 1 + (ring - 1) * segments + (k % segments); };
  for (int k = 0; k < segments; ++k) {
    f.emplace_back(base, at(1, k), at(1, k + 1));
    for (int i = 1; i < rings; ++i) {
      f.emplace_back(at(i, k), at(i + 1, k), at(i + 1, k + 1));
      f.emplace_back(at(i, k), at(i + 1, k + 1), at(i, k + 1));
    }
    f.emplace_back(bottom, at(rings, k + 1), at(rings, k));
  }
}

void Box(const mjtNum* s, Rows& v, Tris& f) {
  const int base = static_cast<int>(v.size());
  for (int i = 0; i < 8; ++i) {
    v.emplace_back((i & 1 ? 1 : -1) * s[0], (i & 2 ? 1 : -1) * s[1], (i & 4 ? 1 : -1) * s[2]);
  }
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    f.emplace_back(base + q[0], base + q[1], base + q[2]);
    f.emplace_back(base + q[0], base + q[2], base + q[3]);
  }
}

void Mesh(const mjModel* m, int id, Rows& v, Tris& f) {
  const int base = static_cast<int>(v.size());
  for (int i = 0; i < m->mesh_vertnum[id]; ++i) {
    const float* p = m->mesh_vert + 3 * (m->mesh_vertadr[id] + i);
    v.emplace_back(p[0], p[1], p[2]);
  }
  for (int i = 0; i < m->mesh_facenum[id]; ++i) {
    const int* t = m->mesh_face + 3 * (m->mesh_faceadr[id] + i);
    f.emplace_back(base + t[0], base + t[1], base + t[2]);
  }
}

}  // namespace

std::vector<int> DrawnGeoms(const mjModel* m) {
  std::vector<int> visual, all;
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_type[g] == mjGEOM_PLANE || m->geom_type[g] == mjGEOM_HFIELD) continue;
    all.push_back(g);
    if (m->geom_contype[g] == 0 && m->geom_conaffinity[g] == 0) visual.push_back(g);
  }
  return visual.empty() ? all : visual;
}

TriMesh GeomsMesh(const mjModel* m, const mjData* d, const std::vector<int>& geoms, int segments) {
  Rows v;
  Tris f;
  for (int g : geoms) {
    const size_t first = v.size();
    const mjtNum* s = m->geom_size + 3 * g;
    switch (m->geom_type[g]) {
      case mjGEOM_SPHERE: Revolution(s[0], s[0], s[0], 0, false, segments, v, f); break;
      case mjGEOM_ELLIPSOID: Revolution(s[0], s[1], s[2], 0, false, segments, v, f); break;
      case mjGEOM_CAPSULE: Revolution(s[0], s[0], s[0], s[1], false, segments, v, f); break;
      case mjGEOM_CYLINDER: Revolution(s[0], s[0], 0, s[1], true, segments, v, f); break;
      case mjGEOM_BOX: Box(s, v, f); break;
      case mjGEOM_MESH: Mesh(m, m->geom_dataid[g], v, f); break;
      default: break;
    }
    const Eigen::Map<const Eigen::Vector3d> pos(d->geom_xpos + 3 * g);
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> rot(d->geom_xmat + 9 * g);
    for (size_t i = first; i < v.size(); ++i) v[i] = pos + rot * v[i];
  }
  TriMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  mesh.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) mesh.vertices.row(static_cast<Eigen::Index>(i)) = v[i];
  for (size_t i = 0; i < f.size(); ++i) mesh.faces.row(static_cast<Eigen::Index>(i)) = f[i];
  return mesh;
}

}  // namespace doasido::retarget
