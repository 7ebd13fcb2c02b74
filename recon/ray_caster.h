// Ray casting onto a triangle mesh with Embree 3: the one place the project
// casts rays (visible-hand centroids and visibility of object points in
// recon; inside tests and solid points of convex decomposition in retarget).
#pragma once

#include <memory>
#include <optional>

#include <Eigen/Core>

#include "core/geometry.h"

namespace doasido::recon {

class RayCaster {
 public:
  using Vertices = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  using Faces = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

  // Builds a scene from one mesh (vertices (V,3), faces (F,3) indexing
  // them; single precision inside Embree). Throws Error("bad_mesh") for a
  // face index out of range and Error("embree") when Embree refuses.
  RayCaster(const Vertices& vertices, const Faces& faces);
  ~RayCaster();
  RayCaster(const RayCaster&) = delete;
  RayCaster& operator=(const RayCaster&) = delete;

  // Distance along `direction` (any length > 0; normalised here) from
  // `origin` to the first triangle hit beyond `t_min`, either side facing;
  // nullopt on a miss.
  std::optional<double> FirstHit(const Vec3& origin, const Vec3& direction,
                                 double t_min = 0) const;

  // Number of surface crossings along the half-line from `origin`; hits
  // closer than `gap` to the previous one count once (a ray through a shared
  // edge meets both triangles). Odd exactly when `origin` is inside a closed
  // mesh.
  int Crossings(const Vec3& origin, const Vec3& direction, double gap = 1e-7) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace doasido::recon
