#include "recon/bundle/bundle.h"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>

#include "core/error.h"
#include "core/file_text.h"
#include "core/json_input.h"
#include "recon/bundle/bundle_layout.h"
#include "recon/bundle/exr_io.h"
#include "recon/bundle/mask_io.h"
#include "recon/bundle/npy.h"

namespace doasido::recon {
namespace fs = std::filesystem;
using layout::kMaskParts;
using layout::MaskMember;
namespace {

constexpr double kUnitTolerance = 1e-3;  // quaternion and gravity norms
// A hand-held object larger than this many metres is a unit mistake (a 5 cm
// object in millimetres spans 50).
constexpr double kMaxObjectExtent = 5.0;

// Reads one bundle folder part by part; each Read* validates its part
// against meta.json, fills b_ and records the part in b_.present.
class Reader {
 public:
  explicit Reader(const fs::path& dir) : dir_(dir), clip_(dir.filename().string()) {
    if (clip_.empty()) clip_ = dir.parent_path().filename().string();
  }

  ClipBundle Read() {
    if (!fs::is_directory(dir_)) Fail("", "", "bundle folder does not exist");
    ReadMeta();
    ReadK();
    ReadDepth();
    ReadPoints();
    for (int i = 0; i < 3; ++i) ReadMasks(i);
    ReadHands();
    ReadMesh();
    ReadPoses();
    ReadCandidates();
    ReadTracks();
    ReadGravity();
    return std::move(b_);
  }

 private:
  [[noreturn]] void Fail(const std::string& rel, const std::string& field,
                         const std::string& what) {
    throw Error("bad_bundle", what,
                {.clip = clip_, .file = rel.empty() ? dir_.string() : (dir_ / rel).string(),
                 .field = field});
  }

  // Re-labels errors from the npy/EXR/PNG layers with the clip (and, for
  // image parts, the bundle field).
  template <typename F>
  auto WithClip(F&& f, const std::string& field = "") -> decltype(f()) {
    try {
      return f();
    } catch (const Error& e) {
      ErrorSite site = e.site();
      site.clip = clip_;
      if (!field.empty()) site.field = field;
      throw Error(e.code() == "io" ? "io" : "bad_bundle", e.message(), site);
    }
  }

  NpzArchive Npz(const std::string& rel) { return WithClip([&] { return ReadNpz(dir_ / rel); }); }

  // Array `key` of `npz` (read from `rel`), checked to be floating point
  // with `shape` (-1: any extent); errors name the file and key.
  const NpyArray& FloatArray(const NpzArchive& npz, const std::string& rel,
                             const std::string& key, const std::vector<std::int64_t>& shape) {
    const std::string file = (dir_ / rel).string();
    return WithClip([&]() -> const NpyArray& {
      const NpyArray& a = RequireKey(npz, key, file);
      CheckFloat(a, file, key);
      CheckShape(a, shape, file, key);
      return a;
    });
  }

  void RequireFinite(const NpyArray& a, const std::string& rel, const std::string& key) {
    for (std::int64_t i = 0; i < a.size(); ++i) {
      if (!std::isfinite(a.AsDouble(i))) {
        Fail(rel, key, "non-finite value at flat index " + std::to_string(i));
      }
    }
  }

  // The frame count T given by meta.json, as an npy extent.
  std::int64_t T() const { return b_.frames; }

  void ReadMeta() {
    const std::string rel = "meta.json";
    const fs::path path = dir_ / rel;
    if (!fs::exists(path)) Fail(rel, "", "meta.json is missing");
    Json meta;
    try {
      meta = ParseJsonInput(ReadFileOrThrow(path, "io", "cannot read meta.json"), {},
                            {.max_depth = 16, .max_bytes = 1u << 20});
    } catch (const Error& e) {
      Fail(rel, "", e.code() + ": " + e.message());
    }
    if (!meta.is_object()) Fail(rel, "", "top level is not an object");
    auto positive_int = [&](const char* key) {
      if (!meta.contains(key)) Fail(rel, key, "missing");
      const Json& v = meta[key];
      if (!v.is_number_integer() || v.get<long long>() <= 0 || v.get<long long>() > (1 << 30)) {
        Fail(rel, key, "must be a positive integer, got " + v.dump());
      }
      return v.get<int>();
    };
    b_.width = positive_int("width");
    b_.height = positive_int("height");
    b_.frames = positive_int("frames");
    if (!meta.contains("fps")) Fail(rel, "fps", "missing");
    if (!meta["fps"].is_number() || !(meta["fps"].get<double>() > 0) ||
        !std::isfinite(meta["fps"].get<double>())) {
      Fail(rel, "fps", "must be a positive number, got " + meta["fps"].dump());
    }
    b_.fps = meta["fps"].get<double>();
    if (!meta.contains("units")) Fail(rel, "units", "missing (must be \"m\")");
    if (meta["units"] != "m") {
      Fail(rel, "units", "must be \"m\" (metres), got " + meta["units"].dump());
    }
    if (meta.contains("producers")) {
      if (!meta["producers"].is_object()) Fail(rel, "producers", "must be an object");
      b_.producers = meta["producers"];
    }
  }

  void ReadK() {
    const std::string rel = "K.npz";
    if (!fs::exists(dir_ / rel)) return;
    const NpzArchive npz = Npz(rel);
    const NpyArray& k = WithClip([&]() -> const NpyArray& { return RequireKey(npz, "K", rel); });
    WithClip([&] { CheckFloat(k, (dir_ / rel).string(), "K"); });
    if (k.ndim() == 2) {
      WithClip([&] { CheckShape(k, {3, 3}, (dir_ / rel).string(), "K"); });
    } else {
      WithClip([&] { CheckShape(k, {T(), 3, 3}, (dir_ / rel).string(), "K"); });
    }
    RequireFinite(k, rel, "K");
    const std::int64_t n = k.ndim() == 2 ? 1 : T();
    for (std::int64_t f = 0; f < n; ++f) {
      Mat3 m;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m(r, c) = k.AsDouble(f * 9 + r * 3 + c);
      }
      if (m(2, 0) != 0 || m(2, 1) != 0 || m(2, 2) != 1 || m(1, 0) != 0 || !(m(0, 0) > 0) ||
          !(m(1, 1) > 0)) {
        Fail(rel, "K", "frame " + std::to_string(f) +
                           " is not a pinhole K (fx, fy > 0, row 2 = [0 0 1], K[1,0] = 0)");
      }
      b_.K.push_back(m);
    }
    b_.present.insert("K");
  }

  // Checks a per-frame folder: every frame file present, none beyond T.
  // Returns false when the folder does not exist.
  bool CheckFrameFolder(const std::string& rel_dir, const std::string& ext,
                        const std::string& field) {
    const fs::path folder = dir_ / rel_dir;
    if (!fs::is_directory(folder)) return false;
    for (int t = 0; t < b_.frames; ++t) {
      const std::string name = FrameFileName(t, ext);
      if (!fs::exists(folder / name)) {
        Fail(rel_dir + "/" + name, field,
             "frame file is missing (meta.json says " + std::to_string(b_.frames) + " frames)");
      }
    }
    for (const auto& entry : fs::directory_iterator(folder)) {
      const std::string name = entry.path().filename().string();
      int index = -1;
      char tail[16] = {0};
      if (name.size() == 6 + ext.size() + 1 &&
          std::sscanf(name.c_str(), "%6d.%15s", &index, tail) == 2 && ext == tail &&
          index >= b_.frames) {
        Fail(rel_dir + "/" + name, field,
             "frame file beyond meta.json's " + std::to_string(b_.frames) + " frames");
      }
    }
    return true;
  }

  void ReadDepth() {
    if (!CheckFrameFolder("depth", "exr", "depth")) return;
    b_.depth.reserve(static_cast<size_t>(b_.frames));
    for (int t = 0; t < b_.frames; ++t) {
      const std::string rel = "depth/" + FrameFileName(t, "exr");
      cv::Mat z = WithClip([&] { return ReadDepthExr(dir_ / rel); }, "depth");
      if (z.cols != b_.width || z.rows != b_.height) {
        Fail(rel, "depth", "image is " + std::to_string(z.cols) + "x" + std::to_string(z.rows) +
                               ", meta.json says " + std::to_string(b_.width) + "x" +
                               std::to_string(b_.height));
      }
      for (int y = 0; y < z.rows; ++y) {
        const float* row = z.ptr<float>(y);
        for (int x = 0; x < z.cols; ++x) {
          if (std::isnan(row[x]) || row[x] < 0 || row[x] == -INFINITY) {
            Fail(rel, "depth", "invalid depth " + std::to_string(row[x]) + " at pixel (x=" +
                                   std::to_string(x) + ", y=" + std::to_string(y) +
                                   "); only +inf or 0 may mark invalid pixels");
          }
        }
      }
      b_.depth.push_back(std::move(z));
    }
    b_.present.insert("depth");
  }

  void ReadPoints() {
    if (!CheckFrameFolder("points", "exr", "points")) return;
    b_.points.reserve(static_cast<size_t>(b_.frames));
    for (int t = 0; t < b_.frames; ++t) {
      const std::string rel = "points/" + FrameFileName(t, "exr");
      cv::Mat p = WithClip([&] { return ReadPointsExr(dir_ / rel); }, "points");
      if (p.cols != b_.width || p.rows != b_.height) {
        Fail(rel, "points", "image is " + std::to_string(p.cols) + "x" + std::to_string(p.rows) +
                                ", meta.json says " + std::to_string(b_.width) + "x" +
                                std::to_string(b_.height));
      }
      b_.points.push_back(std::move(p));
    }
    b_.present.insert("points");
  }

  void ReadMasks(int i) {
    const std::string rel_dir = std::string("masks/") + kMaskParts[i].folder;
    if (!CheckFrameFolder(rel_dir, "png", kMaskParts[i].part)) return;
    std::vector<cv::Mat>& out = b_.*MaskMember(i);
    out.reserve(static_cast<size_t>(b_.frames));
    for (int t = 0; t < b_.frames; ++t) {
      const std::string rel = rel_dir + "/" + FrameFileName(t, "png");
      cv::Mat m = WithClip([&] { return ReadMaskPng(dir_ / rel); }, kMaskParts[i].part);
      if (m.cols != b_.width || m.rows != b_.height) {
        Fail(rel, kMaskParts[i].part,
             "mask is " + std::to_string(m.cols) + "x" + std::to_string(m.rows) +
                 ", meta.json says " + std::to_string(b_.width) + "x" + std::to_string(b_.height));
      }
      out.push_back(std::move(m));
    }
    b_.present.insert(kMaskParts[i].part);
  }

  void ReadHands() {
    const std::string rel = "hands.npz";
    if (!fs::exists(dir_ / rel)) return;
    const NpzArchive npz = Npz(rel);
    if (npz.count("joint_order")) {
      const NpyArray& order = npz.at("joint_order");
      if (order.dtype != DType::kUnicode || order.ToString() != "openpose21") {
        Fail(rel, "joint_order",
             "must be \"openpose21\" (convert MANO order with conventions.h first)");
      }
    }
    for (const std::string side : {"left", "right"}) {
      const std::string jk = side + "_joints", vk = side + "_valid";
      if (!npz.count(jk)) {
        if (npz.count(vk)) Fail(rel, jk, "missing while " + vk + " is present");
        continue;
      }
      HandTrack hand = ReadHandJoints(npz, rel, side);
      ReadHandMesh(npz, rel, side, hand);
      (side == "left" ? b_.hand_left : b_.hand_right) = std::move(hand);
      b_.present.insert("hand_" + side);
    }
  }

  // `side`'s validity and joints per frame from hands.npz (`rel`).
  HandTrack ReadHandJoints(const NpzArchive& npz, const std::string& rel, const std::string& side) {
    const std::string file = (dir_ / rel).string();
    const std::string jk = side + "_joints", vk = side + "_valid";
    HandTrack hand;
    WithClip([&] {
      const NpyArray& valid = RequireKey(npz, vk, file);
      CheckInteger(valid, file, vk);
      CheckShape(valid, {T()}, file, vk);
      const NpyArray& joints = npz.at(jk);
      CheckFloat(joints, file, jk);
      CheckShape(joints, {T(), 21, 3}, file, jk);
    });
    const NpyArray& valid = npz.at(vk);
    const NpyArray& joints = npz.at(jk);
    hand.valid.resize(static_cast<size_t>(T()));
    hand.joints.resize(static_cast<size_t>(T()));
    for (std::int64_t t = 0; t < T(); ++t) {
      hand.valid[static_cast<size_t>(t)] = valid.AsInt(t) != 0;
      Joints21& j = hand.joints[static_cast<size_t>(t)];
      for (int k = 0; k < 63; ++k) j.data()[k] = joints.AsDouble(t * 63 + k);
      if (hand.valid[static_cast<size_t>(t)] && !j.allFinite()) {
        Fail(rel, jk, "non-finite joint in frame " + std::to_string(t) + " marked valid");
      }
    }
    return hand;
  }

  // `side`'s mesh per frame (and its faces) when hands.npz holds one.
  void ReadHandMesh(const NpzArchive& npz, const std::string& rel, const std::string& side,
                    HandTrack& hand) {
    const std::string file = (dir_ / rel).string();
    const std::string verts_key = side + "_verts", faces_key = side + "_faces";
    if (npz.count(verts_key)) {
      const NpyArray& verts = npz.at(verts_key);
      WithClip([&] {
        CheckFloat(verts, file, verts_key);
        CheckShape(verts, {T(), -1, 3}, file, verts_key);
      });
      const std::int64_t v = verts.shape[1];
      hand.verts.resize(static_cast<size_t>(T()));
      for (std::int64_t t = 0; t < T(); ++t) {
        Eigen::MatrixX3d& m = hand.verts[static_cast<size_t>(t)];
        m.resize(v, 3);
        for (std::int64_t r = 0; r < v; ++r) {
          for (int c = 0; c < 3; ++c) m(r, c) = verts.AsDouble((t * v + r) * 3 + c);
        }
        if (v > 0 && m.array().isNaN().all()) {
          m.resize(0, 3);  // the frame has no mesh
        } else if (hand.valid[static_cast<size_t>(t)] && !m.allFinite()) {
          Fail(rel, verts_key, "non-finite vertex in frame " + std::to_string(t) +
                                   " marked valid");
        }
      }
      if (npz.count(faces_key)) {
        const NpyArray& faces = npz.at(faces_key);
        WithClip([&] {
          CheckInteger(faces, file, faces_key);
          CheckShape(faces, {-1, 3}, file, faces_key);
        });
        hand.faces.resize(faces.shape[0], 3);
        for (std::int64_t i = 0; i < faces.size(); ++i) {
          const std::int64_t idx = faces.AsInt(i);
          if (idx < 0 || idx >= v) {
            Fail(rel, faces_key, "vertex index " + std::to_string(idx) + " outside [0, " +
                                     std::to_string(v) + ")");
          }
          hand.faces.data()[i] = static_cast<int>(idx);
        }
      }
    } else if (npz.count(faces_key)) {
      Fail(rel, faces_key, "faces given without " + verts_key);
    }
  }

  // A strict OBJ reader: 'v' and 'f' records only, so that the mesh comes
  // back with exactly the written vertex order and values.
  TriMesh ReadObj(const std::string& rel) {
    std::ifstream in(dir_ / rel);
    if (!in) Fail(rel, "", "cannot open");
    std::vector<double> v;
    std::vector<int> f;
    std::string line;
    long lineno = 0;
    auto bad = [&](const std::string& what) {
      throw Error("bad_bundle", what,
                  {.clip = clip_, .file = (dir_ / rel).string(), .line = lineno, .field = "mesh"});
    };
    while (std::getline(in, line)) {
      ++lineno;
      std::istringstream ls(line);
      std::string tag;
      ls >> tag;
      if (tag == "v") {
        double x, y, z;
        if (!(ls >> x >> y >> z)) bad("malformed vertex");
        if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) bad("non-finite vertex");
        v.insert(v.end(), {x, y, z});
      } else if (tag == "f") {
        std::vector<int> poly;
        std::string tok;
        const int nv = static_cast<int>(v.size() / 3);
        while (ls >> tok) {
          int idx = 0;
          try {
            idx = std::stoi(tok.substr(0, tok.find('/')));
          } catch (const std::exception&) {
            bad("malformed face index '" + tok + "'");
          }
          idx = idx < 0 ? nv + idx : idx - 1;
          if (idx < 0 || idx >= nv) bad("face index '" + tok + "' refers to no vertex");
          poly.push_back(idx);
        }
        if (poly.size() < 3) bad("face with fewer than 3 vertices");
        for (size_t k = 1; k + 1 < poly.size(); ++k) {
          f.insert(f.end(), {poly[0], poly[k], poly[k + 1]});  // fan
        }
      }
    }
    if (f.empty()) bad("no faces");
    TriMesh mesh;
    mesh.vertices.resize(static_cast<Eigen::Index>(v.size() / 3), 3);
    std::copy(v.begin(), v.end(), mesh.vertices.data());
    mesh.faces.resize(static_cast<Eigen::Index>(f.size() / 3), 3);
    std::copy(f.begin(), f.end(), mesh.faces.data());
    return mesh;
  }

  void ReadMesh() {
    for (const char* ext : {"obj", "ply", "glb"}) {
      const std::string rel = std::string("object/mesh.") + ext;
      if (!fs::exists(dir_ / rel)) continue;
      b_.object_mesh = std::string(ext) == "obj" ? ReadObj(rel)
                                                 : WithClip([&] { return LoadMesh(dir_ / rel); });
      const double extent = (b_.object_mesh->Max() - b_.object_mesh->Min()).maxCoeff();
      if (extent > kMaxObjectExtent) {
        Fail(rel, "mesh", "object spans " + std::to_string(extent) +
                              " units; bundle meshes are in metres (millimetres given?)");
      }
      b_.present.insert("object_mesh");
      return;
    }
  }

  Pose PoseAt(const NpyArray& a, std::int64_t offset, const std::string& rel,
              const std::string& key, const std::string& where) {
    Pose p;
    p.t = Vec3(a.AsDouble(offset), a.AsDouble(offset + 1), a.AsDouble(offset + 2));
    p.q = Quat(a.AsDouble(offset + 3), a.AsDouble(offset + 4), a.AsDouble(offset + 5),
               a.AsDouble(offset + 6));
    if (!p.t.allFinite() || !p.q.coeffs().allFinite()) Fail(rel, key, "non-finite pose " + where);
    if (std::abs(p.q.norm() - 1.0) > kUnitTolerance) {
      Fail(rel, key, "quaternion (w x y z) of " + where + " has norm " +
                         std::to_string(p.q.norm()) + ", not 1");
    }
    return p;
  }

  void ReadPoses() {
    const std::string rel = "object/poses.npz";
    if (!fs::exists(dir_ / rel)) return;
    const std::string file = (dir_ / rel).string();
    const NpzArchive npz = Npz(rel);
    const NpyArray& a = FloatArray(npz, rel, "poses", {T(), 7});
    for (std::int64_t t = 0; t < T(); ++t) {
      b_.object_poses.push_back(PoseAt(a, t * 7, rel, "poses", "frame " + std::to_string(t)));
    }
    b_.present.insert("object_poses");
  }

  void ReadCandidates() {
    const std::string rel = "object/candidates.npz";
    if (!fs::exists(dir_ / rel)) return;
    const std::string file = (dir_ / rel).string();
    const NpzArchive npz = Npz(rel);
    WithClip([&] {
      const NpyArray& a = RequireKey(npz, "poses", file);
      CheckFloat(a, file, "poses");
      CheckShape(a, {T(), -1, 7}, file, "poses");
      const NpyArray& s = RequireKey(npz, "scale", file);
      CheckFloat(s, file, "scale");
      CheckShape(s, {T(), a.shape[1]}, file, "scale");
    });
    const NpyArray& a = npz.at("poses");
    const NpyArray& s = npz.at("scale");
    const std::int64_t n = a.shape[1];
    b_.candidates.resize(static_cast<size_t>(T()));
    for (std::int64_t t = 0; t < T(); ++t) {
      for (std::int64_t i = 0; i < n; ++i) {
        const std::string where = "frame " + std::to_string(t) + " sample " + std::to_string(i);
        PoseSample sample;
        sample.pose = PoseAt(a, (t * n + i) * 7, rel, "poses", where);
        sample.scale = s.AsDouble(t * n + i);
        if (!(sample.scale > 0) || !std::isfinite(sample.scale)) {
          Fail(rel, "scale", "scale of " + where + " is " + std::to_string(sample.scale));
        }
        b_.candidates[static_cast<size_t>(t)].push_back(sample);
      }
    }
    b_.present.insert("candidates");
  }

  void ReadTracks() {
    const std::string rel = "tracks.npz";
    if (!fs::exists(dir_ / rel)) return;
    const std::string file = (dir_ / rel).string();
    const NpzArchive npz = Npz(rel);
    WithClip([&] {
      const NpyArray& xy = RequireKey(npz, "xy", file);
      CheckFloat(xy, file, "xy");
      CheckShape(xy, {-1, T(), 2}, file, "xy");
      const std::int64_t n = xy.shape[0];
      const NpyArray& vis = RequireKey(npz, "visible", file);
      CheckInteger(vis, file, "visible");
      CheckShape(vis, {n, T()}, file, "visible");
      const NpyArray& q = RequireKey(npz, "query", file);
      CheckFloat(q, file, "query");
      CheckShape(q, {n, 3}, file, "query");
    });
    const NpyArray& xy = npz.at("xy");
    const NpyArray& vis = npz.at("visible");
    const NpyArray& q = npz.at("query");
    RequireFinite(q, rel, "query");
    const std::int64_t n = xy.shape[0];
    PointTracks tr;
    tr.x.resize(n, T());
    tr.y.resize(n, T());
    tr.visible.resize(n, T());
    tr.query.resize(n, 3);
    for (std::int64_t i = 0; i < n; ++i) {
      for (std::int64_t t = 0; t < T(); ++t) {
        const std::int64_t k = i * T() + t;
        tr.x(i, t) = static_cast<float>(xy.AsDouble(2 * k));
        tr.y(i, t) = static_cast<float>(xy.AsDouble(2 * k + 1));
        tr.visible(i, t) = vis.AsInt(k) != 0 ? 1 : 0;
        if (tr.visible(i, t) && (!std::isfinite(tr.x(i, t)) || !std::isfinite(tr.y(i, t)))) {
          Fail(rel, "xy", "non-finite position of visible track " + std::to_string(i) +
                              " in frame " + std::to_string(t));
        }
      }
      for (int c = 0; c < 3; ++c) tr.query(i, c) = static_cast<float>(q.AsDouble(i * 3 + c));
    }
    b_.tracks = std::move(tr);
    b_.present.insert("tracks");
  }

  void ReadGravity() {
    const std::string rel = "gravity.npz";
    if (!fs::exists(dir_ / rel)) return;
    const std::string file = (dir_ / rel).string();
    const NpzArchive npz = Npz(rel);
    const NpyArray& up = FloatArray(npz, rel, "up", {T(), 3});
    RequireFinite(up, rel, "up");
    for (std::int64_t t = 0; t < T(); ++t) {
      const Vec3 g(up.AsDouble(3 * t), up.AsDouble(3 * t + 1), up.AsDouble(3 * t + 2));
      if (std::abs(g.norm() - 1.0) > kUnitTolerance) {
        Fail(rel, "up", "frame " + std::to_string(t) + " is not a unit vector (norm " +
                            std::to_string(g.norm()) + ")");
      }
      b_.gravity_up.push_back(g);
    }
    b_.present.insert("gravity");
  }

  fs::path dir_;
  std::string clip_;
  ClipBundle b_;
};

}  // namespace

ClipBundle ReadBundle(const fs::path& dir) { return Reader(dir).Read(); }

}  // namespace doasido::recon
