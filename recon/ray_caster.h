// First-hit ray casting onto a triangle mesh with Embree 3: the one place
// recon casts rays (visible-hand centroids, visibility of object points).
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
  // `origin` to the first triangle hit, either side facing; nullopt on a
  // miss.
  std::optional<double> FirstHit(const Vec3& origin, const Vec3& direction) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace doasido::recon
