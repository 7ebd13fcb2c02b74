// Synthetic references for retargeting: a scripted episode (episode.h) as
// the `recon` stage's artifact (recon/reconstruction.h), exact, and the
// same with the errors a monocular reconstruction makes (seed section 3.1,
// REFERENCE.md section 4): a per-clip depth-scale error about the camera,
// a constant hand-object misalignment, per-frame jitter of the hand joints
// and the object pose, and a discontinuity (hand and object jump from one
// frame on, as after a tracking loss).
#pragma once

#include <cstdint>

#include "recon/reconstruction.h"
#include "synth/episode.h"

namespace doasido::synth {

// The episode's hands (left_* only when it has a left hand) and object in the
// world frame (floor z = 0).
// object_mesh is left empty (the caller knows the mesh).
recon::Reconstruction EpisodeReconstruction(const Episode& episode, double fps,
                                            const HandShape& shape = {});

struct ReconstructionNoise {
  double depth_scale = 0.05;     // sd of the relative depth-scale error
  Vec3 camera = Vec3(0.0, -0.45, 0.35);  // scale centre, world frame
  double misalignment = 0.01;    // m, sd per axis of a constant hand offset
  double jitter = 0.003;         // m, sd per axis per frame (hand joints, object)
  double jitter_rot = 0.02;      // rad, sd per axis per frame of the object rotation
  double discontinuity = 0.02;   // m, size of the jump
};

// Applies `noise` to `r` (valid frames), deterministic for `seed`. After
// the scale error the scene is shifted vertically so the object's frame-0
// height is unchanged (the recon stage puts the floor under the object).
void AddReconstructionNoise(recon::Reconstruction& r, const ReconstructionNoise& noise,
                            std::uint64_t seed);

}  // namespace doasido::synth
