#include "retarget/scene/object_surface.h"

#include <limits>

namespace doasido::retarget {

ObjectSurface::ObjectSurface(const mjModel* m, int body) {
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_bodyid[g] != body || m->geom_type[g] != mjGEOM_MESH || !(m->geom_contype[g] & 1)) continue;
    const int mesh = m->geom_dataid[g];
    const float* vert = m->mesh_vert + 3 * m->mesh_vertadr[mesh];
    const int* face = m->mesh_face + 3 * m->mesh_faceadr[mesh];
    auto vertex = [&](int i) { return Vec3(vert[3 * i], vert[3 * i + 1], vert[3 * i + 2]); };
    Vec3 centre = Vec3::Zero();
    for (int i = 0; i < m->mesh_vertnum[mesh]; ++i) centre += vertex(i);
    centre /= std::max(1, m->mesh_vertnum[mesh]);
    Piece piece;
    piece.geom = g;
    for (int f = 0; f < m->mesh_facenum[mesh]; ++f) {
      const Vec3 a = vertex(face[3 * f]), b = vertex(face[3 * f + 1]), c = vertex(face[3 * f + 2]);
      Vec3 n = (b - a).cross(c - a);
      if (n.norm() < 1e-12) continue;
      n.normalize();
      // Outward whatever the file's winding: a convex piece holds its centre.
      if (n.dot(a - centre) < 0) n = -n;
      piece.normals.push_back(n);
      piece.offsets.push_back(n.dot(a));
    }
    if (!piece.normals.empty()) pieces_.push_back(std::move(piece));
  }
}

double ObjectSurface::SignedDistance(const mjData* d, const Vec3& p, Vec3* gradient) const {
  double best = std::numeric_limits<double>::infinity();
  for (const Piece& piece : pieces_) {
    const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> rot(d->geom_xmat + 9 * piece.geom);
    const Vec3 local = rot.transpose() * (p - Eigen::Map<const Vec3>(d->geom_xpos + 3 * piece.geom));
    double inside = -std::numeric_limits<double>::infinity();
    int face = 0;
    for (size_t f = 0; f < piece.normals.size(); ++f) {
      const double s = piece.normals[f].dot(local) - piece.offsets[f];
      if (s > inside) inside = s, face = static_cast<int>(f);
    }
    if (inside < best) {
      best = inside;
      if (gradient) *gradient = rot * piece.normals[face];
    }
  }
  return best;
}

bool ObjectSurface::Measures(const mjModel* m, int g) {
  const int type = m->geom_type[g];
  return type == mjGEOM_SPHERE || type == mjGEOM_CAPSULE || type == mjGEOM_BOX;
}

double ObjectSurface::GeomDistance(const mjModel* m, const mjData* d, int g, Vec3* witness,
                                   Vec3* normal) const {
  if (!Measures(m, g)) return std::numeric_limits<double>::infinity();
  const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> rot(d->geom_xmat + 9 * g);
  const Vec3 centre = Eigen::Map<const Vec3>(d->geom_xpos + 3 * g);
  const mjtNum* size = m->geom_size + 3 * g;
  double radius = 0;
  std::vector<Vec3> core;
  switch (m->geom_type[g]) {
    case mjGEOM_SPHERE:
      radius = size[0];
      core.push_back(centre);
      break;
    case mjGEOM_CAPSULE:
      radius = size[0];
      for (double u : {-1.0, -0.5, 0.0, 0.5, 1.0}) core.push_back(centre + u * size[1] * rot.col(2));
      break;
    default:  // box
      for (int corner = 0; corner < 8; ++corner) {
        const Vec3 sign((corner & 1) ? 1 : -1, (corner & 2) ? 1 : -1, (corner & 4) ? 1 : -1);
        core.push_back(centre + rot * sign.cwiseProduct(Vec3(size[0], size[1], size[2])));
      }
      for (int axis = 0; axis < 3; ++axis) {  // face centres: a face resting on a curved object
        for (double sign : {-1.0, 1.0}) core.push_back(centre + sign * size[axis] * rot.col(axis));
      }
  }
  double best = std::numeric_limits<double>::infinity();
  for (const Vec3& p : core) {
    Vec3 gradient;
    const double distance = SignedDistance(d, p, &gradient) - radius;
    if (distance >= best) continue;
    best = distance;
    if (witness) *witness = p;
    if (normal) *normal = gradient;
  }
  return best;
}

}  // namespace doasido::retarget
