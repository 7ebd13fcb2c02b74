#include "eval/umetrack_hand.h"

#include <cmath>

#include "core/config.h"
#include "core/error.h"
#include "core/file_text.h"
#include "core/json_input.h"

namespace doasido::recon {
namespace {

constexpr int kFrames = 17;  // root + wrist + 3 per finger
constexpr int kUnusedBone = 255;

[[noreturn]] void Bad(const std::filesystem::path& file, const std::string& field,
                      const std::string& why) {
  throw Error("bad_hand_model", why, {.file = file.string(), .field = field});
}

// Row `i` of a (rows, N) numeric array member, checked finite.
template <size_t N>
std::array<double, N> Row(const Json& model, const std::filesystem::path& file,
                          const std::string& key, size_t rows, size_t i) {
  const auto it = model.find(key);
  if (it == model.end() || !it->is_array() || it->size() != rows) {
    Bad(file, key, "expected an array of " + std::to_string(rows) + " rows");
  }
  const Json& row = (*it)[i];
  if (!row.is_array() || row.size() != N) {
    Bad(file, key + "[" + std::to_string(i) + "]", "expected " + std::to_string(N) + " numbers");
  }
  std::array<double, N> out{};
  for (size_t k = 0; k < N; ++k) {
    if (!row[k].is_number() || !std::isfinite(row[k].get<double>())) {
      Bad(file, key + "[" + std::to_string(i) + "]", "not a finite number");
    }
    out[k] = row[k].get<double>();
  }
  return out;
}

Vec3 AsVec3(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

// The 17 skinning frames (hand -> world, lengths in the model's mm).
std::array<Eigen::Affine3d, kFrames> SkinningFrames(const UmeTrackHand& hand,
                                                    const std::array<double, kUmeTrackJoints>& angles,
                                                    const Pose& wrist, HandSide side) {
  const Vec3 mirror(side == HandSide::kRight ? -1 : 1, 1, 1);
  Eigen::Affine3d w = Eigen::Affine3d::Identity();
  w.linear() = wrist.R() * mirror.asDiagonal() * (0.001 * hand.scale);
  w.translation() = wrist.t;
  std::array<Eigen::Affine3d, kFrames> frames;
  frames[0] = frames[1] = w;
  for (int f = 0; f < 5; ++f) {
    Eigen::Affine3d chain = w;
    for (int k = 0; k < 4; ++k) {
      const int j = 4 * f + k;
      const Mat3 r = Eigen::AngleAxisd(angles[j], hand.axes[j]).toRotationMatrix();
      Eigen::Affine3d local = Eigen::Affine3d::Identity();
      local.linear() = r;
      local.translation() = hand.rest[j] - r * hand.rest[j];
      chain = chain * local;
      if (k >= 1) frames[2 + 3 * f + (k - 1)] = chain;
    }
  }
  return frames;
}

std::array<Vec3, kUmeTrackLandmarks> Skin(const UmeTrackHand& hand,
                                          const std::array<Eigen::Affine3d, kFrames>& frames) {
  std::array<Vec3, kUmeTrackLandmarks> out;
  for (int i = 0; i < kUmeTrackLandmarks; ++i) {
    out[i].setZero();
    for (int k = 0; k < 3; ++k) {
      if (hand.landmark_bones[i][k] == kUnusedBone) continue;
      out[i] += hand.landmark_weights[i][k] * (frames[hand.landmark_bones[i][k]] * hand.landmark_rest[i]);
    }
  }
  return out;
}

}  // namespace

UmeTrackHand ReadUmeTrackHand(const std::filesystem::path& profile_json) {
  const Json doc =
      ParseJsonInput(ReadFileOrThrow(profile_json, "io", "cannot read the hand profile"),
                     {.file = profile_json.string()});
  if (!doc.is_object() || !doc.contains("hand_model") || !doc["hand_model"].is_object()) {
    Bad(profile_json, "hand_model", "no hand_model object (not a UmeTrack user profile)");
  }
  const Json& model = doc["hand_model"];
  UmeTrackHand h;
  for (int j = 0; j < kUmeTrackJoints; ++j) {
    const Vec3 axis = AsVec3(Row<3>(model, profile_json, "joint_rotation_axes", kUmeTrackJoints, j));
    if (axis.norm() < 1e-6) Bad(profile_json, "joint_rotation_axes", "a zero rotation axis");
    h.axes[j] = axis.normalized();
    h.rest[j] = AsVec3(Row<3>(model, profile_json, "joint_rest_positions", kUmeTrackJoints, j));
  }
  for (int i = 0; i < kUmeTrackLandmarks; ++i) {
    h.landmark_rest[i] =
        AsVec3(Row<3>(model, profile_json, "landmark_rest_positions", kUmeTrackLandmarks, i));
    const auto bones = Row<3>(model, profile_json, "landmark_rest_bone_indices", kUmeTrackLandmarks, i);
    h.landmark_weights[i] = Row<3>(model, profile_json, "landmark_rest_bone_weights", kUmeTrackLandmarks, i);
    for (int k = 0; k < 3; ++k) {
      const bool used = h.landmark_weights[i][k] != 0;
      if (used && (bones[k] < 0 || bones[k] >= kFrames || bones[k] != std::floor(bones[k]))) {
        Bad(profile_json, "landmark_rest_bone_indices", "bone index outside the 17 skinning frames");
      }
      h.landmark_bones[i][k] = used ? static_cast<int>(bones[k]) : kUnusedBone;
    }
  }
  if (model.contains("hand_scale")) {
    const Json& s = model["hand_scale"];
    if (!s.is_number() || !(s.get<double>() > 0) || !std::isfinite(s.get<double>())) {
      Bad(profile_json, "hand_scale", "not a positive number");
    }
    h.scale = s.get<double>();
  }
  return h;
}

std::array<Vec3, kUmeTrackLandmarks> UmeTrackLandmarks(const UmeTrackHand& hand,
                                                      const std::array<double, kUmeTrackJoints>& angles,
                                                      const Pose& wrist, HandSide side) {
  return Skin(hand, SkinningFrames(hand, angles, wrist, side));
}

Joints21 UmeTrackOpenPose21(const UmeTrackHand& hand,
                            const std::array<double, kUmeTrackJoints>& angles, const Pose& wrist,
                            HandSide side) {
  // OpenPose-21 index -> UmeTrack landmark; -1 = the thumb's CMC (below).
  static constexpr std::array<int, 21> kFromLandmark = {
      5, -1, 6, 7, 0, 8, 9, 10, 1, 11, 12, 13, 2, 14, 15, 16, 3, 17, 18, 19, 4};
  const auto frames = SkinningFrames(hand, angles, wrist, side);
  const auto landmarks = Skin(hand, frames);
  Joints21 j;
  for (int k = 0; k < 21; ++k) {
    if (kFromLandmark[k] >= 0) j.row(k) = landmarks[kFromLandmark[k]].transpose();
  }
  // Joint 1 turns about its own rest position, so frame 2 (after joints 0
  // and 1) carries that point where the thumb's base is.
  j.row(1) = (frames[2] * hand.rest[1]).transpose();
  return j;
}

}  // namespace doasido::recon
