// Triangle meshes: the one mesh type every module passes around, and the one
// place that reads mesh files (through assimp: OBJ, PLY, GLB/GLTF, STL).
#pragma once

#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "core/geometry.h"

namespace doasido {

struct TriMesh {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> vertices;  // (V,3) metres
  Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> faces;        // (F,3) ccw outward

  int num_vertices() const { return static_cast<int>(vertices.rows()); }
  int num_faces() const { return static_cast<int>(faces.rows()); }
  Eigen::Vector3d Min() const { return vertices.colwise().minCoeff(); }
  Eigen::Vector3d Max() const { return vertices.colwise().maxCoeff(); }
  double SurfaceArea() const;
  // Signed volume (positive for a closed outward-oriented mesh).
  double Volume() const;
  // Applies x -> pose * (scale * x) to every vertex.
  TriMesh Transformed(const Pose& pose, double scale = 1.0) const;
};

// Loads every mesh of a file into one TriMesh (node transforms applied,
// triangulated, identical vertices joined). `scale` multiplies coordinates,
// e.g. 0.001 for a file in millimetres. Throws Error("bad_mesh") naming the
// file on failure or when the file has no triangles or NaN coordinates.
TriMesh LoadMesh(const std::filesystem::path& path, double scale = 1.0);

// Writes OBJ (always supported). Throws Error("io") on failure.
void SaveObj(const TriMesh& mesh, const std::filesystem::path& path);

}  // namespace doasido
