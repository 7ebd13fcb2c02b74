// ReconstructHandOnly (declared in recon/align/reconstruct.h): a bundle with hands
// and no object becomes a reconstruction of the hands alone.
#include <algorithm>
#include <cmath>

#include "recon/align/reconstruct.h"

namespace doasido::recon {
namespace {

// The largest frame-to-frame wrist (keypoint 0) displacement of a hand over
// consecutive valid frames, m; 0 with fewer than two.
double MaxWristJump(const std::vector<bool>& valid, const std::vector<Joints21>& joints) {
  double jump = 0;
  for (size_t t = 1; t < joints.size(); ++t) {
    if (valid[t] && valid[t - 1]) jump = std::max(jump, (joints[t].row(0) - joints[t - 1].row(0)).norm());
  }
  return jump;
}

int Count(const std::vector<bool>& v) { return static_cast<int>(std::count(v.begin(), v.end(), true)); }

// A hand track rotated into the gravity-aligned frame (floor not yet applied).
void Rotate(const HandTrack& h, int frames, const Mat3& R, std::vector<bool>& valid,
            std::vector<Joints21>& joints) {
  valid.assign(frames, false);
  joints.assign(frames, Joints21::Zero());
  for (int t = 0; t < frames && static_cast<size_t>(t) < h.joints.size(); ++t) {
    valid[t] = static_cast<size_t>(t) < h.valid.size() ? static_cast<bool>(h.valid[t]) : true;
    if (valid[t]) joints[t] = (h.joints[t] * R.transpose()).eval();
  }
}

}  // namespace

bool IsHandOnly(const ClipBundle& b) {
  const bool object = b.object_mesh || !b.object_poses.empty() || !b.candidates.empty() ||
                      !b.mask_object.empty();
  return !object && (b.hand_left || b.hand_right);
}

ReconOutput ReconstructHandOnly(const ClipBundle& b, const ReconStageConfig& config) {
  ReconOutput out;
  out.gravity = EstimateGravity(b, config.gravity);
  const Mat3 R = UpToZ(out.gravity.up);
  out.camera_to_world = R;
  const int T = b.frames;
  Reconstruction& r = out.reconstruction;
  r.fps = b.fps > 0 ? b.fps : 30.0;
  r.object_valid.assign(T, false);
  r.object_poses.assign(T, Pose::Identity());
  r.right_valid.assign(T, false);
  r.right_joints.assign(T, Joints21::Zero());
  if (b.hand_right) Rotate(*b.hand_right, T, R, r.right_valid, r.right_joints);
  if (b.hand_left) Rotate(*b.hand_left, T, R, r.left_valid, r.left_joints);

  // The floor: kHandOnlyFloorMargin below the lowest joint of either hand.
  double lowest = 1e30;
  const auto lower = [&](const std::vector<bool>& valid, const std::vector<Joints21>& joints) {
    for (size_t t = 0; t < joints.size(); ++t) {
      if (valid[t]) lowest = std::min(lowest, joints[t].col(2).minCoeff());
    }
  };
  lower(r.right_valid, r.right_joints);
  lower(r.left_valid, r.left_joints);
  const double floor_h = lowest < 1e29 ? lowest - kHandOnlyFloorMargin : 0;
  out.floor_offset = floor_h;
  for (auto& j : r.right_joints) j.col(2).array() -= floor_h;
  for (auto& j : r.left_joints) j.col(2).array() -= floor_h;
  r.floor_z = 0;

  const bool gravity_assumed = out.gravity.source == kGravityFromCamera;
  Json& m = out.measurements;
  m[kMeasureFrames] = T;
  m[kMeasureObject] = kObjectNone;
  m[kMeasureGravitySource] = out.gravity.source;
  m[kMeasureGravityAssumed] = gravity_assumed;
  m[kMeasureRightFrames] = Count(r.right_valid);
  m[kMeasureLeftFrames] = Count(r.left_valid);
  m[kMeasureWristJumpMax] = std::max(MaxWristJump(r.right_valid, r.right_joints),
                                     MaxWristJump(r.left_valid, r.left_joints));
  r.info = {{"units", "m"},
            {"object", kObjectNone},
            {"world", "gravity -z, floor z = 0 a fixed margin below the hands' lowest joint"},
            {"gravity", {{"source", out.gravity.source},
                         {"assumed", gravity_assumed},
                         {"up_camera", {out.gravity.up.x(), out.gravity.up.y(), out.gravity.up.z()}}}},
            {"floor", {{"rule", "lowest hand joint minus margin"},
                       {"margin_m", kHandOnlyFloorMargin},
                       {"camera_frame_height", floor_h}}},
            {"producers", b.producers}};
  return out;
}

}  // namespace doasido::recon
