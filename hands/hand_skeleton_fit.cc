#include "hands/hand_skeleton_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <ceres/ceres.h>

#include "core/stage_progress.h"
#include "hands/hand_pnp.h"

namespace doasido::hands {
namespace {

struct Reprojection {
  double u, v, fx, fy, cx, cy, w;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    const T z = x[2] > T(1e-3) ? x[2] : T(1e-3);
    r[0] = T(w) * (T(fx) * x[0] / z + T(cx) - T(u));
    r[1] = T(w) * (T(fy) * x[1] / z + T(cy) - T(v));
    return true;
  }
};

struct Link {
  double w, length;
  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const {
    const T dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    const T squared = dx * dx + dy * dy + dz * dz;
    // The gradient of a norm at zero is undefined; joints never coincide in a fit
    // that starts from a hand, but guard the derivative anyway.
    const T norm = squared > T(1e-12) ? sqrt(squared) : T(1e-6);
    r[0] = T(w) * (norm - T(length));
    return true;
  }
};

struct Shape {
  Vec3 offset;  // the model's joint - wrist, camera axes
  double w;
  template <typename T>
  bool operator()(const T* joint, const T* wrist, T* r) const {
    for (int i = 0; i < 3; ++i) r[i] = T(w) * (joint[i] - wrist[i] - T(offset[i]));
    return true;
  }
};

struct Acceleration {
  double w;
  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, T* r) const {
    for (int i = 0; i < 3; ++i) r[i] = T(w) * (a[i] - T(2) * b[i] + c[i]);
    return true;
  }
};

// A long clip's solve takes minutes: each iteration is a sign of life for
// the worker's watch (core/stage_progress.h).
class ReportProgress : public ceres::IterationCallback {
 public:
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    ReportStageProgress();
    return ceres::SOLVER_CONTINUE;
  }
};

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// The hand's size in the image (keypoint box diagonal), median over frames.
double ImageSize(const Track& track) {
  std::vector<double> sizes;
  for (const auto& o : track.frames) {
    if (!o) continue;
    Eigen::Vector2d lo = o->uv[0], hi = o->uv[0];
    for (const auto& p : o->uv) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    sizes.push_back((hi - lo).norm());
  }
  return std::max(4.0, Median(sizes));
}

// PnP per frame; gaps (and frames PnP could not place) interpolated.
// Returns false when no frame has a pose.
bool Initialise(const Track& track, const Mat3& K, FittedTrack& out,
                std::vector<std::optional<HandPose>>& poses) {
  const size_t n = track.frames.size();
  poses.assign(n, std::nullopt);
  out.joints.assign(n, Joints{});
  out.pnp_joints.assign(n, Joints{});
  out.filled.assign(n, true);
  out.has_pnp.assign(n, false);
  std::vector<int> known;
  for (size_t f = 0; f < n; ++f) {
    if (!track.frames[f]) continue;
    poses[f] = SolveHandPose(*track.frames[f], K);
    if (!poses[f]) continue;
    out.joints[f] = out.pnp_joints[f] = poses[f]->joints;
    out.filled[f] = false;
    out.has_pnp[f] = true;
    known.push_back(static_cast<int>(f));
  }
  if (known.empty()) return false;
  for (size_t f = 0; f < n; ++f) {
    if (!out.filled[f]) continue;
    const auto next = std::lower_bound(known.begin(), known.end(), static_cast<int>(f));
    const int b = next == known.end() ? known.back() : *next;
    const int a = next == known.begin() ? known.front() : *(next - 1);
    const double s = a == b ? 0.0 : (static_cast<double>(f) - a) / (b - a);
    for (int j = 0; j < kJoints; ++j) out.joints[f][j] = (1 - s) * out.joints[a][j] + s * out.joints[b][j];
  }
  return true;
}

void AddFrameResiduals(ceres::Problem& problem, const HandObservation& o, const HandPose& pose,
                       const Mat3& K, double sigma_px, const FitConfig& c, Joints& x) {
  for (int j = 0; j < kJoints; ++j) {
    if (o.confidence[j] <= 0) continue;
    const Reprojection r{o.uv[j].x(), o.uv[j].y(), K(0, 0), K(1, 1), K(0, 2), K(1, 2),
                         std::sqrt(o.confidence[j]) / sigma_px};
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Reprojection, 2, 3>(new Reprojection(r)),
                             new ceres::HuberLoss(c.huber), x[j].data());
  }
  for (int j = 1; j < kJoints; ++j) {
    const Shape s{pose.R * (o.world[j] - o.world[0]), 1.0 / c.shape_sigma_m};
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Shape, 3, 3, 3>(new Shape(s)), nullptr,
                             x[j].data(), x[0].data());
  }
}

double ReprojectionRms(const Track& track, const FittedTrack& fit, const Mat3& K) {
  const Camera cam = Camera::FromK(K, 0, 0);
  double sum = 0;
  int count = 0;
  for (size_t f = 0; f < track.frames.size(); ++f) {
    if (!track.frames[f]) continue;
    for (int j = 0; j < kJoints; ++j) {
      if (track.frames[f]->confidence[j] <= 0) continue;
      sum += (cam.Project(fit.joints[f][j]) - track.frames[f]->uv[j]).squaredNorm();
      ++count;
    }
  }
  return count ? std::sqrt(sum / count) : 0.0;
}

}  // namespace

std::vector<std::pair<int, int>> SkeletonLinks() {
  std::vector<std::pair<int, int>> links;
  for (int j = 1; j < kJoints; ++j) links.emplace_back(j, kParent[j]);
  links.emplace_back(17, 5);  // across the palm
  return links;
}

FittedTrack FitTrack(const Track& track, const Mat3& K, double fps, const FitConfig& c) {
  const auto start = std::chrono::steady_clock::now();
  FittedTrack out;
  out.side = track.side;
  out.first_frame = track.first_frame;
  out.observations = track.frames;
  std::vector<std::optional<HandPose>> poses;
  if (!Initialise(track, K, out, poses)) {
    out.joints.clear();
    return out;
  }
  const size_t n = out.joints.size();
  const std::vector<std::pair<int, int>> links = SkeletonLinks();
  out.link_length.clear();
  for (const auto& [a, b] : links) {
    std::vector<double> lengths;
    for (const auto& o : track.frames) {
      if (o) lengths.push_back((o->world[a] - o->world[b]).norm());
    }
    out.link_length.push_back(Median(lengths));
  }
  ceres::Problem problem;
  const double sigma_px = c.reprojection_sigma * ImageSize(track);
  for (size_t f = 0; f < n; ++f) {
    if (poses[f]) AddFrameResiduals(problem, *track.frames[f], *poses[f], K, sigma_px, c, out.joints[f]);
    for (size_t k = 0; k < links.size(); ++k) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Link, 1, 3, 3>(
                                   new Link{1.0 / c.bone_sigma_m, out.link_length[k]}),
                               nullptr, out.joints[f][links[k].first].data(),
                               out.joints[f][links[k].second].data());
    }
  }
  const double accel_w = 1.0 / (c.acceleration_sigma_ms2 / (fps * fps));
  for (size_t f = 1; f + 1 < n; ++f) {
    for (int j = 0; j < kJoints; ++j) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Acceleration, 3, 3, 3, 3>(
                                   new Acceleration{accel_w}),
                               nullptr, out.joints[f - 1][j].data(), out.joints[f][j].data(),
                               out.joints[f + 1][j].data());
    }
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = c.max_iterations;
  options.num_threads = 1;
  ReportProgress progress;
  options.callbacks.push_back(&progress);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  out.iterations = static_cast<int>(summary.iterations.size());
  out.reprojection_rms_px = ReprojectionRms(track, out, K);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace doasido::hands
