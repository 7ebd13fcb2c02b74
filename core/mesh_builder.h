// Building a TriMesh vertex by vertex and face by face, for meshes made in
// code (synthetic objects, the test mug).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/geometry.h"
#include "core/mesh.h"

namespace doasido {

struct MeshBuilder {
  std::vector<Vec3> vertices;
  std::vector<Eigen::Vector3i> faces;
  // Triangles naming one vertex twice (the pole of a sphere-like grid) are
  // left out when set.
  bool drop_degenerate = false;

  // Index of the added vertex.
  int Add(const Vec3& p) {
    vertices.push_back(p);
    return static_cast<int>(vertices.size()) - 1;
  }
  void Tri(int a, int b, int c) {
    if (drop_degenerate && (a == b || b == c || a == c)) return;
    faces.emplace_back(a, b, c);
  }
  // Two triangles; counter-clockwise seen from outside.
  void Quad(int a, int b, int c, int d) {
    Tri(a, b, c);
    Tri(a, c, d);
  }
  TriMesh Mesh() const {
    TriMesh m;
    m.vertices.resize(static_cast<Eigen::Index>(vertices.size()), 3);
    m.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
    for (size_t i = 0; i < vertices.size(); ++i) m.vertices.row(i) = vertices[i].transpose();
    for (size_t i = 0; i < faces.size(); ++i) m.faces.row(i) = faces[i].transpose();
    return m;
  }
};

}  // namespace doasido
