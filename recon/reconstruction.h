// The reconstruction artifact: what the `recon` stage writes for a clip and
// what every later stage (retarget_kinematic, retarget, dataset, review,
// deploy) reads. One metric, gravity-aligned hand-object trajectory.
//
// Folder layout (<artifacts>/<clip>/recon/):
//   reconstruction.npz
//     fps            (1,)      f8
//     right_valid    (T,)      u1   right hand seen in frame t
//     right_joints   (T,21,3)  f8   OpenPose-21, world frame, metres (NaN rows when not valid)
//     left_valid, left_joints   the left hand the same way; absent when the clip has none
//     object_valid   (T,)      u1   object pose known in frame t
//     object_poses   (T,7)     f8   object->world: t xyz + quaternion wxyz (NaN when not valid)
//     floor_z        (1,)      f8   height of the support surface (0 by construction)
//   object.obj       the object mesh in its own frame, metres (absent: no object mesh)
//   reconstruction.json  provenance and quality: gravity source, alignment
//                        statistics, which frames were filled; free-form JSON object
//
// World frame: gravity is -z, the floor is the plane z = floor_z (0) under the
// object's resting pose; x, y follow the first frame's camera, made horizontal.
#pragma once

#include <filesystem>
#include <vector>

#include "core/config.h"
#include "core/geometry.h"
#include "recon/bundle/bundle.h"

namespace doasido::recon {

// The `recon` stage's name (stages/recon_stage.h): its queue name, config
// section and the artifact folder that holds this reconstruction, here so
// that its readers (dataset, review) need not the stages.
inline constexpr const char* kReconStageName = "recon";

struct Reconstruction {
  double fps = 30;
  std::vector<bool> right_valid;          // (T)
  std::vector<Joints21> right_joints;     // (T) world frame, metres
  // The left hand, the same way; both empty when the clip has none (and in
  // files written before it was recorded).
  std::vector<bool> left_valid;           // (T) or empty
  std::vector<Joints21> left_joints;      // (T) or empty
  std::vector<bool> object_valid;         // (T)
  std::vector<Pose> object_poses;         // (T) object->world
  double floor_z = 0;
  std::filesystem::path object_mesh;      // OBJ in the object's frame; empty = none
  Json info = Json::object();             // reconstruction.json

  int frames() const { return static_cast<int>(right_valid.size()); }
};

// The file names inside a reconstruction folder.
inline constexpr const char* kReconstructionNpz = "reconstruction.npz";
inline constexpr const char* kReconstructionJson = "reconstruction.json";
inline constexpr const char* kReconstructionMesh = "object.obj";

// Writes `r` into `dir` (created). When r.object_mesh names a file outside
// `dir` it is copied to dir/object.obj. Throws Error("io") naming the file.
void WriteReconstruction(const Reconstruction& r, const std::filesystem::path& dir);

// Reads a folder written by WriteReconstruction. Checks shapes, frame
// counts, finite values on valid frames and unit quaternions; throws
// Error("bad_reconstruction") naming the file and the array.
Reconstruction ReadReconstruction(const std::filesystem::path& dir);

}  // namespace doasido::recon
