#include "eval/mug_mesh.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/mesh_builder.h"

namespace doasido::retarget {
namespace {

// The mug's grids close at poles, where a row's vertices coincide.
struct Builder : MeshBuilder {
  Builder() { drop_degenerate = true; }
};

// The closed profile (r, z) the cup is turned from: axis bottom -> outer
// wall -> rim -> inner wall -> inside bottom -> axis. Traversed this way,
// MakeCup's triangles face out of the solid.
std::vector<std::pair<double, double>> MugProfile(const MugShape& s) {
  const double ri = s.radius - s.wall;
  const std::vector<std::pair<double, double>> corners = {
      {0, 0}, {s.radius, 0}, {s.radius, s.height}, {ri, s.height}, {ri, s.bottom}, {0, s.bottom}};
  // Edges split into pieces of at most 1.5 cm: well-shaped triangles rather
  // than full-height slivers (decomposition merges compact patches first).
  std::vector<std::pair<double, double>> profile = {corners[0]};
  for (size_t i = 0; i + 1 < corners.size(); ++i) {
    const auto [r0, z0] = corners[i];
    const auto [r1, z1] = corners[i + 1];
    const int pieces = std::max(1, static_cast<int>(std::ceil(std::hypot(r1 - r0, z1 - z0) / 0.015)));
    for (int k = 1; k <= pieces; ++k) {
      profile.emplace_back(r0 + (r1 - r0) * k / pieces, z0 + (z1 - z0) * k / pieces);
    }
  }
  return profile;
}

// The cup: the profile turned about the z axis in s.segments steps.
TriMesh MakeCup(const MugShape& s) {
  Builder b;
  const std::vector<std::pair<double, double>> profile = MugProfile(s);
  const int n = s.segments;
  std::vector<std::vector<int>> id(profile.size(), std::vector<int>(n));
  for (size_t i = 0; i < profile.size(); ++i) {
    const auto [r, z] = profile[i];
    if (r == 0) {
      const int pole = b.Add(Vec3(0, 0, z));
      for (int j = 0; j < n; ++j) id[i][j] = pole;
      continue;
    }
    for (int j = 0; j < n; ++j) {
      const double t = 2 * M_PI * j / n;
      id[i][j] = b.Add(Vec3(r * std::cos(t), r * std::sin(t), z));
    }
  }
  for (size_t i = 0; i + 1 < profile.size(); ++i) {
    for (int j = 0; j < n; ++j) {
      const int k = (j + 1) % n;
      b.Tri(id[i][j], id[i][k], id[i + 1][k]);
      b.Tri(id[i][j], id[i + 1][k], id[i + 1][j]);
    }
  }
  TriMesh cup = b.Mesh();
  if (cup.Volume() < 0) cup.faces.col(1).swap(cup.faces.col(2));
  return cup;
}

// The handle: the outer half of a torus in the xz-plane, its ends sunk into
// the wall, closed by flat caps.
TriMesh MakeHandle(const MugShape& s) {
  const Vec3 c(s.radius - 0.0005, 0, 0.5 * s.height);
  const int nu = s.segments / 2, nv = 16;
  Builder h;
  std::vector<std::vector<int>> hid(nu + 1, std::vector<int>(nv));
  for (int i = 0; i <= nu; ++i) {
    const double u = -M_PI / 2 + M_PI * i / nu;
    const Vec3 dir(std::cos(u), 0, std::sin(u));
    for (int j = 0; j < nv; ++j) {
      const double w = 2 * M_PI * j / nv;
      hid[i][j] = h.Add(c + (s.handle_radius + s.handle_tube * std::cos(w)) * dir +
                        s.handle_tube * std::sin(w) * Vec3::UnitY());
    }
  }
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const int k = (j + 1) % nv;
      h.Tri(hid[i][j], hid[i][k], hid[i + 1][k]);
      h.Tri(hid[i][j], hid[i + 1][k], hid[i + 1][j]);
    }
  }
  for (int end : {0, nu}) {
    const double u = -M_PI / 2 + M_PI * end / nu;
    const int centre = h.Add(c + s.handle_radius * Vec3(std::cos(u), 0, std::sin(u)));
    for (int j = 0; j < nv; ++j) {
      const int k = (j + 1) % nv;
      if (end == 0) {
        h.Tri(centre, hid[end][k], hid[end][j]);
      } else {
        h.Tri(centre, hid[end][j], hid[end][k]);
      }
    }
  }
  TriMesh handle = h.Mesh();
  if (handle.Volume() < 0) handle.faces.col(1).swap(handle.faces.col(2));
  return handle;
}

}  // namespace

TriMesh MakeMug(const MugShape& s) {
  const TriMesh cup = MakeCup(s);
  const TriMesh handle = MakeHandle(s);
  TriMesh out;
  out.vertices.resize(cup.num_vertices() + handle.num_vertices(), 3);
  out.vertices << cup.vertices, handle.vertices;
  out.faces.resize(cup.num_faces() + handle.num_faces(), 3);
  out.faces << cup.faces, (handle.faces.array() + cup.num_vertices()).matrix();
  return out;
}

}  // namespace doasido::retarget
