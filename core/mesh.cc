#include "core/mesh.h"

#include <cmath>
#include <fstream>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "core/error.h"

namespace doasido {
namespace {

void AppendNode(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent,
                std::vector<Vec3>& verts, std::vector<Eigen::Vector3i>& faces) {
  const aiMatrix4x4 transform = parent * node->mTransformation;
  for (unsigned m = 0; m < node->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[node->mMeshes[m]];
    const int base = static_cast<int>(verts.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D p = transform * mesh->mVertices[v];
      verts.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines carry no surface
      faces.emplace_back(base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]);
    }
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c) {
    AppendNode(scene, node->mChildren[c], transform, verts, faces);
  }
}

}  // namespace

double TriMesh::SurfaceArea() const {
  double area = 0;
  for (int f = 0; f < num_faces(); ++f) {
    const Vec3 a = vertices.row(faces(f, 0)), b = vertices.row(faces(f, 1)),
               c = vertices.row(faces(f, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

double TriMesh::Volume() const {
  double vol = 0;
  for (int f = 0; f < num_faces(); ++f) {
    const Vec3 a = vertices.row(faces(f, 0)), b = vertices.row(faces(f, 1)),
               c = vertices.row(faces(f, 2));
    vol += a.dot(b.cross(c)) / 6.0;
  }
  return vol;
}

TriMesh TriMesh::Transformed(const Pose& pose, double scale) const {
  TriMesh out = *this;
  for (int v = 0; v < num_vertices(); ++v) {
    const Vec3 p = vertices.row(v).transpose() * scale;
    out.vertices.row(v) = (pose * p).transpose();
  }
  return out;
}

TriMesh LoadMesh(const std::filesystem::path& path, double scale) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(
      path.string(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                         aiProcess_SortByPType | aiProcess_DropNormals);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    throw Error("bad_mesh", std::string("assimp cannot read it: ") + importer.GetErrorString(),
                {.file = path.string()});
  }
  std::vector<Vec3> verts;
  std::vector<Eigen::Vector3i> faces;
  AppendNode(scene, scene->mRootNode, aiMatrix4x4(), verts, faces);
  if (faces.empty()) throw Error("bad_mesh", "no triangles", {.file = path.string()});
  TriMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) {
    if (!verts[i].allFinite()) {
      throw Error("bad_mesh", "vertex " + std::to_string(i) + " is not finite",
                  {.file = path.string(), .field = "vertices"});
    }
    mesh.vertices.row(static_cast<Eigen::Index>(i)) = verts[i].transpose() * scale;
  }
  mesh.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) mesh.faces.row(static_cast<Eigen::Index>(i)) = faces[i];
  return mesh;
}

void SaveObj(const TriMesh& mesh, const std::filesystem::path& path) {
  std::ofstream out(path);
  if (!out) throw Error("io", "cannot write mesh", {.file = path.string()});
  out.precision(9);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    out << "v " << mesh.vertices(v, 0) << ' ' << mesh.vertices(v, 1) << ' ' << mesh.vertices(v, 2)
        << '\n';
  }
  for (int f = 0; f < mesh.num_faces(); ++f) {
    out << "f " << mesh.faces(f, 0) + 1 << ' ' << mesh.faces(f, 1) + 1 << ' '
        << mesh.faces(f, 2) + 1 << '\n';
  }
  if (!out) throw Error("io", "write failed (disk full?)", {.file = path.string()});
}

}  // namespace doasido
