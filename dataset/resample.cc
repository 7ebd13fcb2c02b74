#include "dataset/resample.h"

#include <algorithm>
#include <cmath>

namespace doasido::dataset {

std::vector<double> ResamplePositions(std::size_t frames, double from_fps, double to_fps) {
  std::vector<double> out;
  if (frames == 0) return out;
  const double last = static_cast<double>(frames - 1);
  for (std::size_t k = 0;; ++k) {
    const double p = static_cast<double>(k) * from_fps / to_fps;
    if (p > last + 1e-9) break;
    out.push_back(std::min(p, last));
  }
  return out;
}

namespace {

template <typename T>
std::vector<T> Nearest(const std::vector<T>& v, const std::vector<double>& positions) {
  std::vector<T> out;
  if (v.empty()) return out;
  for (double p : positions) out.push_back(v[std::min(v.size() - 1, static_cast<std::size_t>(std::lround(p)))]);
  return out;
}

std::vector<Eigen::VectorXd> Linear(const std::vector<Eigen::VectorXd>& v, const std::vector<double>& positions) {
  std::vector<Eigen::VectorXd> out;
  if (v.empty()) return out;
  for (double p : positions) {
    const std::size_t a = std::min(v.size() - 1, static_cast<std::size_t>(std::floor(p)));
    const std::size_t b = std::min(v.size() - 1, a + 1);
    const double w = p - static_cast<double>(a);
    out.push_back((1 - w) * v[a] + w * v[b]);
  }
  return out;
}

}  // namespace

retarget::HandTrajectory ResampleTrajectory(const retarget::HandTrajectory& t, double fps) {
  if (t.fps == fps || t.qpos.empty()) return t;
  const std::vector<double> positions = ResamplePositions(t.qpos.size(), t.fps, fps);
  retarget::HandTrajectory out = t;
  out.fps = fps;
  out.qpos = Linear(t.qpos, positions);
  out.ctrl = Linear(t.ctrl, positions);
  out.fingertip_error = Nearest(t.fingertip_error, positions);
  out.reference_keypoints = Nearest(t.reference_keypoints, positions);
  out.valid.clear();
  out.object_poses.clear();
  for (double p : positions) {
    const std::size_t a = static_cast<std::size_t>(std::floor(p));
    const std::size_t b = std::min(t.qpos.size() - 1, a + 1);
    const double w = p - static_cast<double>(a);
    if (!t.valid.empty()) out.valid.push_back(t.valid[a] && t.valid[b]);
    if (!t.object_poses.empty()) {
      const Pose& pa = t.object_poses[a];
      const Pose& pb = t.object_poses[std::min(t.object_poses.size() - 1, b)];
      out.object_poses.push_back({pa.q.slerp(w, pb.q), (1 - w) * pa.t + w * pb.t});
    }
  }
  return out;
}

}  // namespace doasido::dataset
