// Which of two seen hands holds the object: the one a single robot hand
// retargets with dynamics. A clip of a person moving a cup with one hand
// while the other rests on the table (02_cups) would otherwise put the
// resting right hand into the simulation and leave the object untouched.
#pragma once

#include "core/mesh.h"
#include "recon/reconstruction.h"

namespace doasido::retarget {

// True when `r` has both hands and its left hand's fingertips are nearer
// the posed object (its mesh `mesh`) than its right hand's: the median over
// the frames where the hand and the object are both valid of the nearest
// fingertip-to-vertex distance. False without a left hand, an object or a
// frame to compare.
bool LeftHandHoldsObject(const recon::Reconstruction& r, const TriMesh& mesh);

// `r` without its right hand (right_valid all false): a reconstruction
// whose only hand is the one that holds the object.
recon::Reconstruction KeepOnlyLeftHand(recon::Reconstruction r);

}  // namespace doasido::retarget
