#include "recon/reconstruction.h"

#include <cmath>
#include <fstream>

#include "core/error.h"
#include "recon/bundle/npy.h"

namespace doasido::recon {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

[[noreturn]] void Bad(const std::filesystem::path& file, const std::string& field,
                      const std::string& what) {
  throw Error("bad_reconstruction", what, {.file = file.string(), .field = field});
}

std::vector<std::uint8_t> Bytes(const std::vector<bool>& v) {
  return std::vector<std::uint8_t>(v.begin(), v.end());
}

// A (T) integer array as flags, converting Error("bad_bundle") from the npz
// helpers into this artifact's code.
template <typename Fn>
auto Checked(const std::filesystem::path& file, Fn&& fn) {
  try {
    return fn();
  } catch (const Error& e) {
    if (e.code() == "bad_reconstruction") throw;
    Bad(file, e.site().field, e.message());
  }
}

// Reads <side>_valid (t) and <side>_joints (t, 21, 3); valid frames must be finite.
void ReadHand(const NpzArchive& npz, const std::filesystem::path& file, const std::string& side,
              std::int64_t t, std::vector<bool>& valid, std::vector<Joints21>& joints) {
  const std::string name = file.string(), valid_key = side + "_valid", joints_key = side + "_joints";
  const NpyArray& v = RequireKey(npz, valid_key, name);
  CheckInteger(v, name, valid_key);
  CheckShape(v, {t}, name, valid_key);
  const NpyArray& j = RequireKey(npz, joints_key, name);
  CheckFloat(j, name, joints_key);
  CheckShape(j, {t, 21, 3}, name, joints_key);
  const std::vector<double> values = j.AsDoubleVector();
  for (std::int64_t f = 0; f < t; ++f) {
    valid.push_back(v.AsInt(f) != 0);
    const Joints21 k = Eigen::Map<const Joints21>(values.data() + f * 63);
    if (valid.back() && !k.allFinite()) Bad(file, joints_key, "non-finite joint in valid frame " + std::to_string(f));
    joints.push_back(k);
  }
}

}  // namespace

void WriteReconstruction(const Reconstruction& r, const std::filesystem::path& dir) {
  const auto t = static_cast<std::int64_t>(r.right_valid.size());
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  NpzArchive npz;
  // A hand's arrays: <side>_valid (T) and <side>_joints (T, 21, 3), NaN where not seen.
  const auto write_hand = [&](const std::string& side, std::vector<bool> valid,
                              const std::vector<Joints21>& hand) {
    valid.resize(static_cast<size_t>(t), false);
    std::vector<double> joints(static_cast<size_t>(t) * 63, kNaN);
    for (std::int64_t f = 0; f < t && f < static_cast<std::int64_t>(hand.size()); ++f) {
      if (valid[f]) std::copy(hand[f].data(), hand[f].data() + 63, joints.begin() + f * 63);
    }
    npz[side + "_valid"] = MakeArray<std::uint8_t>({t}, Bytes(valid));
    npz[side + "_joints"] = MakeArray<double>({t, 21, 3}, joints);
  };
  write_hand("right", r.right_valid, r.right_joints);
  if (!r.left_valid.empty()) write_hand("left", r.left_valid, r.left_joints);
  std::vector<double> poses(static_cast<size_t>(t) * 7, kNaN);
  for (std::int64_t f = 0; f < t && f < static_cast<std::int64_t>(r.object_poses.size()); ++f) {
    if (!r.object_valid.empty() && !r.object_valid[f]) continue;
    const Pose& p = r.object_poses[f];
    const double v[7] = {p.t.x(), p.t.y(), p.t.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()};
    std::copy(v, v + 7, poses.begin() + f * 7);
  }
  std::vector<bool> object_valid = r.object_valid;
  object_valid.resize(static_cast<size_t>(t), false);
  npz["fps"] = MakeArray<double>({1}, {r.fps});
  npz["object_valid"] = MakeArray<std::uint8_t>({t}, Bytes(object_valid));
  npz["object_poses"] = MakeArray<double>({t, 7}, poses);
  npz["floor_z"] = MakeArray<double>({1}, {r.floor_z});
  WriteNpz(dir / kReconstructionNpz, npz);

  if (!r.object_mesh.empty()) {
    const auto target = dir / kReconstructionMesh;
    if (!std::filesystem::equivalent(r.object_mesh, target, ec)) {
      std::filesystem::copy_file(r.object_mesh, target,
                                 std::filesystem::copy_options::overwrite_existing, ec);
      if (ec) throw Error("io", "cannot copy object mesh: " + ec.message(),
                          {.file = r.object_mesh.string()});
    }
  }
  const auto json_path = dir / kReconstructionJson;
  std::ofstream out(json_path);
  out << r.info.dump(2) << "\n";
  if (!out) throw Error("io", "cannot write", {.file = json_path.string()});
}

Reconstruction ReadReconstruction(const std::filesystem::path& dir) {
  const auto file = dir / kReconstructionNpz;
  if (!std::filesystem::is_regular_file(file)) Bad(file, "", "no reconstruction file");
  const NpzArchive npz = ReadNpz(file);
  const std::string name = file.string();
  Reconstruction r;
  Checked(file, [&] {
    const NpyArray& fps = RequireKey(npz, "fps", name);
    CheckFloat(fps, name, "fps");
    r.fps = fps.AsDouble(0);
    const NpyArray& valid = RequireKey(npz, "right_valid", name);
    CheckInteger(valid, name, "right_valid");
    CheckShape(valid, {-1}, name, "right_valid");
    const std::int64_t t = valid.shape[0];
    ReadHand(npz, file, "right", t, r.right_valid, r.right_joints);
    if (npz.count("left_valid") || npz.count("left_joints")) {
      ReadHand(npz, file, "left", t, r.left_valid, r.left_joints);
    }
    const NpyArray& ovalid = RequireKey(npz, "object_valid", name);
    CheckInteger(ovalid, name, "object_valid");
    CheckShape(ovalid, {t}, name, "object_valid");
    const NpyArray& poses = RequireKey(npz, "object_poses", name);
    CheckFloat(poses, name, "object_poses");
    CheckShape(poses, {t, 7}, name, "object_poses");
    const NpyArray& floor = RequireKey(npz, "floor_z", name);
    CheckFloat(floor, name, "floor_z");
    r.floor_z = floor.AsDouble(0);
    const std::vector<double> p = poses.AsDoubleVector();
    for (std::int64_t f = 0; f < t; ++f) {
      r.object_valid.push_back(ovalid.AsInt(f) != 0);
      Pose pose;
      pose.t = Vec3(p[f * 7], p[f * 7 + 1], p[f * 7 + 2]);
      pose.q = Quat(p[f * 7 + 3], p[f * 7 + 4], p[f * 7 + 5], p[f * 7 + 6]);
      if (r.object_valid.back()) {
        if (!pose.t.allFinite() || !pose.q.coeffs().allFinite() ||
            std::abs(pose.q.norm() - 1) > 1e-3) {
          Bad(file, "object_poses", "bad pose in valid frame " + std::to_string(f));
        }
      }
      r.object_poses.push_back(pose);
    }
    return 0;
  });
  if (!(r.fps > 0) || !std::isfinite(r.fps)) Bad(file, "fps", "fps must be positive");
  if (!std::isfinite(r.floor_z)) Bad(file, "floor_z", "floor_z is not finite");
  if (std::filesystem::is_regular_file(dir / kReconstructionMesh)) {
    r.object_mesh = dir / kReconstructionMesh;
  }
  const auto json_path = dir / kReconstructionJson;
  if (std::filesystem::is_regular_file(json_path)) {
    std::ifstream in(json_path);
    r.info = Json::parse(in, nullptr, false);
    if (r.info.is_discarded() || !r.info.is_object()) {
      Bad(json_path, "", "not a JSON object");
    }
  }
  return r;
}

}  // namespace doasido::recon
