// A lone left hand onto the right robot hand, with everything it touches:
// the world reflected through its x = 0 plane (z, gravity's axis, is left
// alone), so that a mirror image of the clip has a right hand holding the
// mirror image of the object. A reflection is not a rotation, so the
// object is mirrored in its own frame (vertices x -> -x, faces reversed to
// stay outward) and its pose (R, t) becomes (S R S, S t) with
// S = diag(-1, 1, 1): S (R p + t) = (S R S)(S p) + S t for every point p.
#pragma once

#include <vector>

#include "core/geometry.h"
#include "core/mesh.h"
#include "recon/reconstruction.h"
#include "robot/trajectory/format.h"

namespace doasido::retarget {

// Keypoints (world frame) through the x = 0 plane: a left hand becomes a
// right one moving as the left did in a mirror.
std::vector<Keypoints21> MirrorKeypoints(std::vector<Keypoints21> hand);
// An object->world pose for the mirrored mesh: quaternion (w, x, y, z) ->
// (w, x, -y, -z), translation x -> -x.
Pose MirrorPose(const Pose& pose);
std::vector<Pose> MirrorPoses(std::vector<Pose> poses);
// The mesh reflected through its own x = 0 plane, faces reversed.
TriMesh MirrorMesh(TriMesh mesh);

// `r` with its left hand mirrored into the right hand's place (left
// emptied) and its object poses mirrored; the mesh that goes with it is
// MirrorMesh of r's. For a reconstruction whose only hand is the left.
recon::Reconstruction MirrorLeftOntoRight(recon::Reconstruction r);

}  // namespace doasido::retarget
