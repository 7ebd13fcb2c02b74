// The clip bundle: the per-clip folder in which foundation models (or the
// synthetic world) hand their outputs to reconstruction. Layout and
// conventions are REFERENCE.md §3; this file is its one reader and writer,
// so recon reads exactly what synth writes.
//
//   meta.json             width, height, frames, fps, units "m", "producers"
//   K.npz                 K (3,3) or (T,3,3) float64, pixels
//   depth/%06d.exr        metric depth, float32; inf or 0 = invalid
//   points/%06d.exr       point map, float32 channels X, Y, Z (optional)
//   masks/{object,hand_left,hand_right}/%06d.png   8-bit 0/255
//   hands.npz             left_valid (T) u1, left_joints (T,21,3) f8,
//                         left_verts (T,V,3) f8, left_faces (F,3) i4, same
//                         for right_; joint_order: "openpose21"
//   object/mesh.obj       object-local, metres (.ply or .glb also read)
//   object/poses.npz      poses (T,7) f8: t xyz + quaternion wxyz, object->camera
//   object/candidates.npz poses (T,N,7) f8, scale (T,N) f8
//   tracks.npz            xy (N,T,2) f4 px, visible (N,T) u1, query (N,3) f4 (t,y,x)
//   gravity.npz           up (T,3) f8 unit vector, camera frame
//
// The dtypes above are what WriteBundle writes; ReadBundle accepts f4 or f8
// for any float array and u1, b1, i4 or i8 for any integer array.
// All geometry is in OpenCV camera axes (x right, y down, z forward),
// metres. Every part except meta.json is optional; `present` says which
// were found. Readers of model outputs in other conventions (SAM 3D's
// PyTorch3D frame, MoGe's normalised K, ...) convert into this one with
// recon/bundle/conventions.h.
#pragma once

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "core/config.h"
#include "core/geometry.h"
#include "core/mesh.h"

namespace doasido::recon {

using Joints21 = Eigen::Matrix<double, 21, 3, Eigen::RowMajor>;

struct HandTrack {
  std::vector<bool> valid;                 // (T)
  std::vector<Joints21> joints;            // (T) camera frame, metres, OpenPose-21
  std::vector<Eigen::MatrixX3d> verts;     // (T) of (V,3); empty when absent; a frame
                                           // without a mesh is (0,3) (NaN rows on disk)
  Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> faces;  // (F,3)
};

struct PoseSample {
  Pose pose;
  double scale = 1.0;
};

struct PointTracks {
  Eigen::MatrixXf x, y;   // (N,T) pixels
  Eigen::Matrix<std::uint8_t, Eigen::Dynamic, Eigen::Dynamic> visible;  // (N,T)
  Eigen::MatrixX3f query;  // (N,3) as (t, y, x)
};

struct ClipBundle {
  // meta.json
  int width = 0;
  int height = 0;
  int frames = 0;
  double fps = 0;
  Json producers = Json::object();  // which tool made each part
  // K.npz: one entry (constant) or one per frame.
  std::vector<Mat3> K;
  std::vector<cv::Mat> depth;  // CV_32F (H,W) per frame
  std::vector<cv::Mat> points;  // CV_32FC3 (H,W) camera-frame XYZ per frame; non-finite = invalid
  std::vector<cv::Mat> mask_object, mask_hand_left, mask_hand_right;  // CV_8U 0/255
  std::optional<HandTrack> hand_left, hand_right;
  std::optional<TriMesh> object_mesh;
  std::vector<Pose> object_poses;                      // (T) object->camera
  std::vector<std::vector<PoseSample>> candidates;     // (T,N)
  std::optional<PointTracks> tracks;
  std::vector<Vec3> gravity_up;                        // (T)

  // Filled by ReadBundle (ignored by WriteBundle): the parts found, named
  // "K", "depth", "points", "mask_object", "mask_hand_left", "mask_hand_right",
  // "hand_left", "hand_right", "object_mesh", "object_poses", "candidates",
  // "tracks", "gravity".
  std::set<std::string> present;

  // K of frame t (the constant K when only one is stored). Requires !K.empty().
  const Mat3& KAt(int t) const { return K.size() == 1 ? K[0] : K.at(static_cast<size_t>(t)); }
};

// Writes meta.json and every non-empty part into `dir` (created if needed;
// files of the same name are replaced, frame files beyond `frames` in the
// per-frame folders written are removed, other files are left alone). Masks
// are written 0/255 (any non-zero input pixel becomes 255); npz parts are
// stored uncompressed; the mesh is written as object/mesh.obj with
// round-trip precision. Output is byte-identical for identical input.
// Throws Error("bad_bundle") naming the field when the struct is
// inconsistent (a per-frame part whose length is not `frames`, an image of
// the wrong size or type, ragged candidates), Error("io") naming the file.
void WriteBundle(const ClipBundle& bundle, const std::filesystem::path& dir);

// Reads and validates. Throws Error("bad_bundle") naming the file and field
// for a wrong shape or dtype, NaN or inf where not allowed, a missing frame
// file (named), an image size that disagrees with meta.json, or units other
// than "m". Allowed non-finite values: depth +inf (invalid pixel); hand
// joints/verts of frames whose `valid` is 0; track positions where not
// visible. ErrorSite::clip is the bundle folder's name. The object mesh is
// read from object/mesh.obj, .ply or .glb (first found; OBJ is read exactly,
// the others through assimp); a mesh spanning more than 5 units is rejected
// as not being in metres.
ClipBundle ReadBundle(const std::filesystem::path& dir);

// "000042.exr": the file name of frame `t` in a per-frame folder.
std::string FrameFileName(int t, const std::string& extension);

}  // namespace doasido::recon
