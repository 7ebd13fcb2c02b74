#include "recon/bundle/conventions.h"

#include <cmath>
#include <string>

#include "core/error.h"

namespace doasido::recon {

Quat Sam3dQuatToColumn(const Quat& q_row) { return q_row.conjugate(); }

Vec3 PyTorch3dToOpenCv(const Vec3& p) { return {-p.x(), -p.y(), p.z()}; }

Mat3 PyTorch3dToOpenCvMatrix() { return Eigen::Vector3d(-1, -1, 1).asDiagonal(); }

Vec3 Sam3dGlbToObjectLocal(const Vec3& p) { return {p.x(), -p.z(), p.y()}; }

TriMesh Sam3dGlbMeshToObjectLocal(const TriMesh& glb) {
  TriMesh out = glb;
  for (int v = 0; v < glb.num_vertices(); ++v) {
    out.vertices.row(v) = Sam3dGlbToObjectLocal(glb.vertices.row(v).transpose()).transpose();
  }
  return out;
}

PoseSample Sam3dPoseToOpenCv(const Quat& q_row, const Vec3& t_pytorch3d, double scale) {
  const Mat3 r = PyTorch3dToOpenCvMatrix() * Sam3dQuatToColumn(q_row).toRotationMatrix();
  PoseSample out;
  out.pose.q = Quat(r).normalized();
  out.pose.t = PyTorch3dToOpenCv(t_pytorch3d);
  out.scale = scale;
  return out;
}

Mat3 MogeIntrinsicsToPixels(const Mat3& k_norm, int width, int height) {
  Mat3 k = Eigen::Vector3d(width, height, 1).asDiagonal() * k_norm;
  k(0, 2) -= 0.5;
  k(1, 2) -= 0.5;
  return k;
}

Vec3 GeoCalibUp(const Vec3& geocalib_gravity) { return geocalib_gravity.normalized(); }

Vec3 PhysicalGravityDirection(const Vec3& up) { return -up.normalized(); }

double ManoToMetres(ManoSource source) { return source == ManoSource::kManopth ? 1e-3 : 1.0; }

std::array<int, 5> ManoFingertipVertices(ManoSource source) {
  if (source == ManoSource::kManopth) return {745, 317, 444, 556, 673};
  return {744, 320, 443, 554, 671};
}

Joints21 ManoToOpenPose21(const Eigen::MatrixX3d& native16, const Eigen::MatrixX3d& verts,
                          ManoSource source) {
  if (native16.rows() != 16) {
    throw Error("bad_array", "MANO joints have " + std::to_string(native16.rows()) +
                                 " rows, expected 16", {.field = "joints"});
  }
  if (verts.rows() != 778) {
    throw Error("bad_array", "MANO mesh has " + std::to_string(verts.rows()) +
                                 " vertices, expected 778", {.field = "verts"});
  }
  Eigen::Matrix<double, 21, 3> extended;
  extended.topRows<16>() = native16;
  const std::array<int, 5> tips = ManoFingertipVertices(source);
  for (int i = 0; i < 5; ++i) extended.row(16 + i) = verts.row(tips[static_cast<size_t>(i)]);
  Joints21 out;
  for (int i = 0; i < 21; ++i) {
    out.row(i) = extended.row(kManoToOpenPose21[static_cast<size_t>(i)]) * ManoToMetres(source);
  }
  return out;
}

bool JointsLookLikeMillimetres(const Joints21& joints) {
  // OpenPose-21: wrist 0, middle MCP 9.
  return (joints.row(9) - joints.row(0)).norm() > 1.0;
}

Eigen::Vector3f TapirQuery(int frame, float x, float y) {
  return {static_cast<float>(frame), y, x};
}

int TapirQueryFrame(const Eigen::Vector3f& query) {
  return static_cast<int>(std::lround(query(0)));
}

Eigen::Vector2f TapirQueryPixel(const Eigen::Vector3f& query) { return {query(2), query(1)}; }

PointTracks TracksFromTapir(const NpyArray& tracks, const NpyArray& occluded,
                            const NpyArray& query_points) {
  auto bad = [](const std::string& field, const std::string& what) {
    throw Error("bad_array", what, {.field = field});
  };
  if (!tracks.is_float() || tracks.ndim() != 3 || tracks.shape[2] != 2) {
    bad("tracks", "expected float (N, T, 2), got " + DTypeName(tracks.dtype, tracks.item_size) +
                      " " + tracks.ShapeString());
  }
  const std::int64_t n = tracks.shape[0], t = tracks.shape[1];
  if (!occluded.is_integer() || occluded.ndim() != 2 || occluded.shape[0] != n ||
      occluded.shape[1] != t) {
    bad("occluded", "expected bool (" + std::to_string(n) + ", " + std::to_string(t) + "), got " +
                        DTypeName(occluded.dtype, occluded.item_size) + " " +
                        occluded.ShapeString());
  }
  if (!query_points.is_float() || query_points.ndim() != 2 || query_points.shape[0] != n ||
      query_points.shape[1] != 3) {
    bad("query_points", "expected float (" + std::to_string(n) + ", 3), got " +
                            query_points.ShapeString());
  }
  PointTracks out;
  out.x.resize(n, t);
  out.y.resize(n, t);
  out.visible.resize(n, t);
  out.query.resize(n, 3);
  for (std::int64_t i = 0; i < n; ++i) {
    for (std::int64_t f = 0; f < t; ++f) {
      out.x(i, f) = static_cast<float>(tracks.AsDouble((i * t + f) * 2));
      out.y(i, f) = static_cast<float>(tracks.AsDouble((i * t + f) * 2 + 1));
      out.visible(i, f) = occluded.AsInt(i * t + f) != 0 ? 0 : 1;
    }
    for (int c = 0; c < 3; ++c) {
      out.query(i, c) = static_cast<float>(query_points.AsDouble(i * 3 + c));
    }
  }
  return out;
}

}  // namespace doasido::recon
