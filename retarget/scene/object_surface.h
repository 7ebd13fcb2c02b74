// The surface of the simulated object as the kinematic retargeting sees it:
// a signed distance to the union of the object's convex collision pieces
// (the dilated hulls scene_builder.h writes), posed by the model's current
// kinematics.
//
// Each piece is the intersection of its faces' half-spaces, so its signed
// distance is max_f (n_f . p - c_f): exact inside a piece and wherever the
// nearest feature of the piece is a face, a lower bound near its edges and
// corners (the fingertip terms that use it are about touching faces). The
// union takes the minimum over pieces.
#pragma once

#include <vector>

#include "core/geometry.h"
#include "robot/mj_model.h"

namespace doasido::retarget {

class ObjectSurface {
 public:
  // The mesh geoms of `body` that collide with the hand (contype bit 1, so
  // the seed's base plate, which touches only the floor, is left out).
  // Empty when the body has none.
  ObjectSurface(const mjModel* m, int body);

  bool empty() const { return pieces_.empty(); }

  // Signed distance of world point `p` (m; negative inside) with the geoms
  // where `d`'s kinematics (mj_kinematics) put them; `gradient` (may be
  // null) receives its derivative with respect to p, a unit world vector.
  double SignedDistance(const mjData* d, const Vec3& p, Vec3* gradient = nullptr) const;

  // Whether GeomDistance measures geom `g`: spheres, capsules and boxes.
  static bool Measures(const mjModel* m, int g);
  // Signed distance from a (hand) geom to the object: the least, over
  // points of the geom's core (a sphere's centre; five points along a
  // capsule's segment; a box's corners and face centres), of SignedDistance minus the core's
  // radius. `witness` and `normal` (may be null) receive that point (world)
  // and SignedDistance's gradient there. +inf for a geom Measures refuses.
  double GeomDistance(const mjModel* m, const mjData* d, int g, Vec3* witness = nullptr,
                      Vec3* normal = nullptr) const;

 private:
  struct Piece {
    int geom = -1;
    std::vector<Vec3> normals;    // outward, geom frame
    std::vector<double> offsets;  // n . x = offset on the face's plane
  };
  std::vector<Piece> pieces_;
};

}  // namespace doasido::retarget
