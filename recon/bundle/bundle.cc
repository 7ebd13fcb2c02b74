#include "recon/bundle/bundle.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>

#include "core/error.h"
#include "recon/bundle/bundle_layout.h"
#include "recon/bundle/exr_io.h"
#include "recon/bundle/mask_io.h"
#include "recon/bundle/npy.h"

namespace doasido::recon {
namespace fs = std::filesystem;
using layout::kMaskParts;
using layout::MaskMember;
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

[[noreturn]] void BadStruct(const std::string& field, const std::string& what) {
  throw Error("bad_bundle", what, {.field = field});
}

void CheckLength(size_t n, int frames, const std::string& field) {
  if (static_cast<int>(n) != frames) {
    BadStruct(field, "holds " + std::to_string(n) + " frames, meta says " + std::to_string(frames));
  }
}

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw Error("io", "cannot create file", {.file = path.string()});
  out << text;
  if (!out) throw Error("io", "write failed (disk full?)", {.file = path.string()});
}

void MakeDir(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error("io", "cannot create folder: " + ec.message(), {.file = dir.string()});
}

// Creates a per-frame folder and removes frame files numbered `frames` or
// above left by an earlier, longer write (the reader rejects them).
void PrepareFrameFolder(const fs::path& folder, int frames, const std::string& ext) {
  MakeDir(folder);
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    int index = -1;
    char tail[16] = {0};
    if (name.size() == 6 + 1 + ext.size() &&
        std::sscanf(name.c_str(), "%6d.%15s", &index, tail) == 2 && ext == tail &&
        index >= frames) {
      std::error_code ec;
      fs::remove(entry.path(), ec);
      if (ec) {
        throw Error("io", "cannot remove stale frame: " + ec.message(),
                    {.file = entry.path().string()});
      }
    }
  }
}

void AppendPose(std::vector<double>& out, const Pose& p) {
  out.insert(out.end(), {p.t.x(), p.t.y(), p.t.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()});
}

void AddHand(NpzArchive& npz, const std::string& side, const HandTrack& hand, int frames) {
  CheckLength(hand.valid.size(), frames, side + "_valid");
  CheckLength(hand.joints.size(), frames, side + "_joints");
  std::vector<std::uint8_t> valid(hand.valid.begin(), hand.valid.end());
  npz[side + "_valid"] = MakeArray<std::uint8_t>({frames}, valid);
  std::vector<double> joints;
  joints.reserve(static_cast<size_t>(frames) * 63);
  for (const Joints21& j : hand.joints) joints.insert(joints.end(), j.data(), j.data() + 63);
  npz[side + "_joints"] = MakeArray<double>({frames, 21, 3}, joints);
  if (!hand.verts.empty()) {
    CheckLength(hand.verts.size(), frames, side + "_verts");
    Eigen::Index v = 0;
    for (const Eigen::MatrixX3d& m : hand.verts) v = std::max(v, m.rows());
    std::vector<double> verts;
    verts.reserve(static_cast<size_t>(frames * v * 3));
    for (const Eigen::MatrixX3d& m : hand.verts) {
      // A frame without a mesh (hand not seen) is stored as NaN rows.
      if (m.rows() == 0) {
        verts.insert(verts.end(), static_cast<size_t>(v * 3), kNaN);
        continue;
      }
      if (m.rows() != v) BadStruct(side + "_verts", "vertex count changes between frames");
      for (Eigen::Index r = 0; r < v; ++r) verts.insert(verts.end(), {m(r, 0), m(r, 1), m(r, 2)});
    }
    if (v > 0) npz[side + "_verts"] = MakeArray<double>({frames, v, 3}, verts);
  }
  if (hand.faces.rows() > 0) npz[side + "_faces"] = FromEigen(hand.faces);
}

void WriteObjExact(const TriMesh& mesh, const fs::path& path) {
  std::string text;
  char buf[128];
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    std::snprintf(buf, sizeof(buf), "v %.17g %.17g %.17g\n", mesh.vertices(v, 0),
                  mesh.vertices(v, 1), mesh.vertices(v, 2));
    text += buf;
  }
  for (int f = 0; f < mesh.num_faces(); ++f) {
    std::snprintf(buf, sizeof(buf), "f %d %d %d\n", mesh.faces(f, 0) + 1, mesh.faces(f, 1) + 1,
                  mesh.faces(f, 2) + 1);
    text += buf;
  }
  WriteText(path, text);
}


// The parts of WriteBundle, each checked against the bundle's frame count
// and size before it is written.

// K.npz: one 3x3 matrix, or one a frame.
void WriteIntrinsics(const ClipBundle& b, const fs::path& dir) {
  if (b.K.size() != 1) CheckLength(b.K.size(), b.frames, "K");
  std::vector<double> k;
  for (const Mat3& m : b.K) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) k.push_back(m(r, c));
    }
  }
  const std::vector<std::int64_t> shape =
      b.K.size() == 1 ? std::vector<std::int64_t>{3, 3} : std::vector<std::int64_t>{b.frames, 3, 3};
  WriteNpz(dir / "K.npz", {{"K", MakeArray<double>(shape, k)}});
}

// Per-frame images (depth and points as EXR, masks as PNG), one folder each.
void WriteImages(const ClipBundle& b, const fs::path& dir) {
  auto check_image = [&](const cv::Mat& m, int type, const std::string& field, int t) {
    if (m.type() != type || m.cols != b.width || m.rows != b.height) {
      BadStruct(field, "frame " + std::to_string(t) + " is not a " + std::to_string(b.width) +
                           "x" + std::to_string(b.height) + " image of the expected type");
    }
  };
  if (!b.depth.empty()) {
    CheckLength(b.depth.size(), b.frames, "depth");
    PrepareFrameFolder(dir / "depth", b.frames, "exr");
    for (int t = 0; t < b.frames; ++t) {
      check_image(b.depth[static_cast<size_t>(t)], CV_32FC1, "depth", t);
      WriteDepthExr(dir / "depth" / FrameFileName(t, "exr"), b.depth[static_cast<size_t>(t)]);
    }
  }
  if (!b.points.empty()) {
    CheckLength(b.points.size(), b.frames, "points");
    PrepareFrameFolder(dir / "points", b.frames, "exr");
    for (int t = 0; t < b.frames; ++t) {
      check_image(b.points[static_cast<size_t>(t)], CV_32FC3, "points", t);
      WritePointsExr(dir / "points" / FrameFileName(t, "exr"), b.points[static_cast<size_t>(t)]);
    }
  }
  for (int i = 0; i < 3; ++i) {
    const std::vector<cv::Mat>& masks = b.*MaskMember(i);
    if (masks.empty()) continue;
    CheckLength(masks.size(), b.frames, kMaskParts[i].part);
    const fs::path folder = dir / "masks" / kMaskParts[i].folder;
    PrepareFrameFolder(folder, b.frames, "png");
    for (int t = 0; t < b.frames; ++t) {
      check_image(masks[static_cast<size_t>(t)], CV_8UC1, kMaskParts[i].part, t);
      WriteMaskPng(folder / FrameFileName(t, "png"), masks[static_cast<size_t>(t)]);
    }
  }
}

// object/: the mesh, its poses and the candidate poses with their scales.
void WriteObject(const ClipBundle& b, const fs::path& dir) {
  if (b.object_mesh || !b.object_poses.empty() || !b.candidates.empty()) MakeDir(dir / "object");
  if (b.object_mesh) WriteObjExact(*b.object_mesh, dir / "object" / "mesh.obj");
  if (!b.object_poses.empty()) {
    CheckLength(b.object_poses.size(), b.frames, "object_poses");
    std::vector<double> poses;
    for (const Pose& p : b.object_poses) AppendPose(poses, p);
    WriteNpz(dir / "object" / "poses.npz", {{"poses", MakeArray<double>({b.frames, 7}, poses)}});
  }
  if (b.candidates.empty()) return;
  CheckLength(b.candidates.size(), b.frames, "candidates");
  const size_t n = b.candidates[0].size();
  std::vector<double> poses, scale;
  for (const auto& frame : b.candidates) {
    if (frame.size() != n) BadStruct("candidates", "sample count changes between frames");
    for (const PoseSample& s : frame) {
      AppendPose(poses, s.pose);
      scale.push_back(s.scale);
    }
  }
  const auto nn = static_cast<std::int64_t>(n);
  WriteNpz(dir / "object" / "candidates.npz",
           {{"poses", MakeArray<double>({b.frames, nn, 7}, poses)},
            {"scale", MakeArray<double>({b.frames, nn}, scale)}});
}

// tracks.npz: N point tracks over the frames and their queries.
void WriteTracks(const PointTracks& tr, int frames, const fs::path& dir) {
  const Eigen::Index n = tr.x.rows();
  if (tr.x.cols() != frames || tr.y.rows() != n || tr.y.cols() != frames ||
      tr.visible.rows() != n || tr.visible.cols() != frames || tr.query.rows() != n) {
    BadStruct("tracks", "x, y, visible must be (N, frames) and query (N, 3)");
  }
  std::vector<float> xy, query;
  std::vector<std::uint8_t> vis;
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int t = 0; t < frames; ++t) {
      xy.insert(xy.end(), {tr.x(i, t), tr.y(i, t)});
      vis.push_back(tr.visible(i, t) != 0 ? 1 : 0);
    }
    query.insert(query.end(), {tr.query(i, 0), tr.query(i, 1), tr.query(i, 2)});
  }
  WriteNpz(dir / "tracks.npz", {{"xy", MakeArray<float>({n, frames, 2}, xy)},
                                {"visible", MakeArray<std::uint8_t>({n, frames}, vis)},
                                {"query", MakeArray<float>({n, 3}, query)}});
}

}  // namespace

std::string FrameFileName(int t, const std::string& extension) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%06d.", t);
  return buf + extension;
}

void WriteBundle(const ClipBundle& b, const fs::path& dir) {
  if (b.width <= 0 || b.height <= 0) BadStruct("width", "image size must be positive");
  if (b.frames <= 0) BadStruct("frames", "must be positive");
  if (!(b.fps > 0)) BadStruct("fps", "must be positive");
  MakeDir(dir);
  Json meta = {{"width", b.width}, {"height", b.height}, {"frames", b.frames},
               {"fps", b.fps},     {"units", "m"},        {"producers", b.producers}};
  WriteText(dir / "meta.json", meta.dump(2) + "\n");
  if (!b.K.empty()) WriteIntrinsics(b, dir);
  WriteImages(b, dir);
  if (b.hand_left || b.hand_right) {
    NpzArchive npz;
    npz["joint_order"] = MakeStringArray("openpose21");
    if (b.hand_left) AddHand(npz, "left", *b.hand_left, b.frames);
    if (b.hand_right) AddHand(npz, "right", *b.hand_right, b.frames);
    WriteNpz(dir / "hands.npz", npz);
  }
  WriteObject(b, dir);
  if (b.tracks) WriteTracks(*b.tracks, b.frames, dir);
  if (!b.gravity_up.empty()) {
    CheckLength(b.gravity_up.size(), b.frames, "gravity_up");
    std::vector<double> up;
    for (const Vec3& g : b.gravity_up) up.insert(up.end(), {g.x(), g.y(), g.z()});
    WriteNpz(dir / "gravity.npz", {{"up", MakeArray<double>({b.frames, 3}, up)}});
  }
}

}  // namespace doasido::recon
