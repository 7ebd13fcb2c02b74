// The clip bundle: the per-clip folder in which foundation models (or the
// synthetic world) hand their outputs to reconstruction. Layout and
// conventions are REFERENCE.md §3; this file is its one reader and writer,
// so recon reads exactly what synth writes.
//
//   meta.json             width, height, frames, fps, units "m", "producers"
//   K.npz                 K (3,3) or (T,3,3) float64, pixels
//   depth/%06d.exr        metric depth, float32; inf or 0 = invalid
//   masks/{object,hand_left,hand_right}/%06d.png   8-bit 0/255
//   hands.npz             left_valid (T) u1, left_joints (T,21,3) f8,
//                         left_verts (T,V,3) f8, left_faces (F,3) i4, same
//                         for right_; joint_order: "openpose21"
//   object/mesh.obj       object-local, metres
//   object/poses.npz      poses (T,7) f8: t xyz + quaternion wxyz, object->camera
//   object/candidates.npz poses (T,N,7) f8, scale (T,N) f8
//   tracks.npz            xy (N,T,2) f4 px, visible (N,T) u1, query (N,3) f4 (t,y,x)
//   gravity.npz           up (T,3) f8 unit vector, camera frame
//
// All geometry is in OpenCV camera axes (x right, y down, z forward),
// metres. Every part except meta.json is optional; `present` says which
// were found. Readers of model outputs in other conventions (SAM 3D's
// PyTorch3D frame, MoGe's normalised K, ...) convert into this one.
#pragma once

#include <filesystem>
#include <optional>
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
  std::vector<Eigen::MatrixX3d> verts;     // (T) of (V,3); empty when absent
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
  std::vector<cv::Mat> mask_object, mask_hand_left, mask_hand_right;  // CV_8U 0/255
  std::optional<HandTrack> hand_left, hand_right;
  std::optional<TriMesh> object_mesh;
  std::vector<Pose> object_poses;                      // (T) object->camera
  std::vector<std::vector<PoseSample>> candidates;     // (T,N)
  std::optional<PointTracks> tracks;
  std::vector<Vec3> gravity_up;                        // (T)
};

// Writes every non-empty part. Throws Error("io") naming the file.
void WriteBundle(const ClipBundle& bundle, const std::filesystem::path& dir);

// Reads and validates. Throws Error("bad_bundle") naming the file and field
// for a wrong shape, NaN, a missing frame, or a size that disagrees with
// meta.json.
ClipBundle ReadBundle(const std::filesystem::path& dir);

}  // namespace doasido::recon
