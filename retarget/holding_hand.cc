#include "retarget/holding_hand.h"

#include <algorithm>
#include <limits>
#include <vector>

#include "core/hand_keypoints.h"

namespace doasido::retarget {
namespace {

// The median over frames of the nearest fingertip-to-vertex distance; +inf
// without a frame where hand and object are both valid.
double MedianTipDistance(const std::vector<bool>& valid, const std::vector<recon::Joints21>& joints,
                         const recon::Reconstruction& r, const TriMesh& mesh) {
  std::vector<double> per_frame;
  const size_t T = std::min({valid.size(), joints.size(), r.object_valid.size(), r.object_poses.size()});
  for (size_t t = 0; t < T; ++t) {
    if (!valid[t] || !r.object_valid[t]) continue;
    double best = std::numeric_limits<double>::infinity();
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Vec3 p = r.object_poses[t] * Vec3(mesh.vertices.row(v).transpose());
      for (int k : kFingertips) best = std::min(best, (joints[t].row(k).transpose() - p).norm());
    }
    per_frame.push_back(best);
  }
  if (per_frame.empty()) return std::numeric_limits<double>::infinity();
  auto mid = per_frame.begin() + static_cast<std::ptrdiff_t>(per_frame.size() / 2);
  std::nth_element(per_frame.begin(), mid, per_frame.end());
  return *mid;
}

}  // namespace

bool LeftHandHoldsObject(const recon::Reconstruction& r, const TriMesh& mesh) {
  if (mesh.num_vertices() == 0 || r.left_valid.empty()) return false;
  const double left = MedianTipDistance(r.left_valid, r.left_joints, r, mesh);
  const double right = MedianTipDistance(r.right_valid, r.right_joints, r, mesh);
  return left < right;
}

recon::Reconstruction KeepOnlyLeftHand(recon::Reconstruction r) {
  std::fill(r.right_valid.begin(), r.right_valid.end(), false);
  return r;
}

}  // namespace doasido::retarget
