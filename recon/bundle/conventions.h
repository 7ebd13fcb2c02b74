// Conversions from the conventions foundation models write in to the clip
// bundle's one convention (OpenCV camera axes: x right, y down, z forward;
// metres; pixel centres at integer coordinates; quaternions w, x, y, z acting
// on column vectors). Each function is one "trap" of REFERENCE.md §3; model
// adapters call them on read so that nothing downstream has to know which
// tool made a part.
#pragma once

#include <array>

#include <Eigen/Core>

#include "core/geometry.h"
#include "core/mesh.h"
#include "recon/bundle/bundle.h"
#include "recon/bundle/npy.h"

namespace doasido::recon {

// ---- SAM 3D ---------------------------------------------------------------

// SAM 3D rotates row vectors, p_row' = p_row * R(q): the column-vector
// rotation is R(q)^T, i.e. the conjugate quaternion.
Quat Sam3dQuatToColumn(const Quat& q_row);

// PyTorch3D camera axes (x left, y up, z forward) to OpenCV axes:
// diag(-1, -1, 1) * p. The map is its own inverse.
Vec3 PyTorch3dToOpenCv(const Vec3& p);
Mat3 PyTorch3dToOpenCvMatrix();

// SAM 3D's exported GLB is Y-up; the object-local frame its pose acts on is
// Z-up: local = (x, -z, y) of the GLB coordinates (a +90 degree turn about x).
Vec3 Sam3dGlbToObjectLocal(const Vec3& p);
// Applies Sam3dGlbToObjectLocal to every vertex (faces unchanged: the map is
// a rotation, so orientation is kept).
TriMesh Sam3dGlbMeshToObjectLocal(const TriMesh& glb);

// A SAM 3D pose (row-vector quaternion, translation and scale, all in the
// PyTorch3D camera frame) as an object->camera pose in OpenCV axes:
//   x_cv = F * (R(q)^T * (scale * x_local) + t),  F = diag(-1, -1, 1).
// Since F * R(q)^T is a proper rotation, the result is a Pose plus the scale.
PoseSample Sam3dPoseToOpenCv(const Quat& q_row, const Vec3& t_pytorch3d, double scale);

// ---- MoGe -----------------------------------------------------------------

// MoGe's intrinsics are normalised by the image size with pixel centres at
// (i + 0.5) / W: K_pixel = diag(W, H, 1) * K_norm, then cx, cy -= 0.5.
Mat3 MogeIntrinsicsToPixels(const Mat3& k_norm, int width, int height);

// ---- GeoCalib -------------------------------------------------------------

// GeoCalib's `gravity` is the camera-frame "up" direction (what the bundle's
// gravity.npz stores, normalised); physical gravity points the other way.
Vec3 GeoCalibUp(const Vec3& geocalib_gravity);
Vec3 PhysicalGravityDirection(const Vec3& up);

// ---- MANO -----------------------------------------------------------------

// Which MANO implementation produced joints and vertices: manopth works in
// millimetres and picks fingertip vertices 745, 317, 444, 556, 673; smplx
// works in metres and picks 744, 320, 443, 554, 671 (thumb, index, middle,
// ring, pinky).
enum class ManoSource { kManopth, kSmplx };

// Factor that takes the source's lengths to metres (0.001 or 1).
double ManoToMetres(ManoSource source);
// Fingertip vertex ids, thumb to pinky.
std::array<int, 5> ManoFingertipVertices(ManoSource source);

// MANO native joint order is wrist 0, index 1-3, middle 4-6, pinky 7-9,
// ring 10-12, thumb 13-15. Appending the five fingertips (thumb..pinky as
// 16-20) and taking these indices gives OpenPose-21 order (wrist; thumb,
// index, middle, ring, pinky, each base to tip).
inline constexpr std::array<int, 21> kManoToOpenPose21 = {
    0, 13, 14, 15, 16, 1, 2, 3, 17, 4, 5, 6, 18, 10, 11, 12, 19, 7, 8, 9, 20};

// OpenPose-21 joints in metres from MANO's 16 native joints (16,3) and its
// 778 vertices (778,3), both in the source's units. Throws
// Error("bad_array") naming the field when a shape is wrong.
Joints21 ManoToOpenPose21(const Eigen::MatrixX3d& native16, const Eigen::MatrixX3d& verts,
                          ManoSource source);

// Whether joints (OpenPose-21) look like millimetres rather than metres:
// the wrist-to-middle-MCP length of a human hand is 6-12 cm, so a value
// above 1 means millimetres. Lets readers reject a unit mix-up.
bool JointsLookLikeMillimetres(const Joints21& joints);

// ---- TAPIR / BootsTAPIR ---------------------------------------------------

// TAPIR's tracks are [x, y] pixels; its query points are (t, y, x). These
// build and split a query row in that order.
Eigen::Vector3f TapirQuery(int frame, float x, float y);
int TapirQueryFrame(const Eigen::Vector3f& query);
Eigen::Vector2f TapirQueryPixel(const Eigen::Vector3f& query);  // (x, y)

// Tracks from TAPIR's output arrays as a Python adapter saves them:
// `tracks` (N, T, 2) float as [x, y], `occluded` (N, T) bool or integer,
// `query_points` (N, 3) float as (t, y, x). Visible = not occluded. Throws
// Error("bad_array") naming the array on a wrong shape or dtype.
PointTracks TracksFromTapir(const NpyArray& tracks, const NpyArray& occluded,
                            const NpyArray& query_points);

}  // namespace doasido::recon
