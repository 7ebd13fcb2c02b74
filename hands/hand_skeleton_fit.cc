#include "hands/hand_skeleton_fit.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/stage_progress.h"
#include "hands/hand_outliers.h"
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

// Residuals in metres are divided by the track's scale (1 at the
// template's or the model's size): a hand twice as large and twice as far
// projects alike, and each of these would otherwise prefer the smaller one
// (the acceleration above all), overruling the size prior. Divided, only
// the prior (and perspective) sets the size.
//
// A link's length against the track's: `length` times the track's scale.
struct Link {
  double w, length;
  template <typename T>
  bool operator()(const T* a, const T* b, const T* scale, T* r) const {
    const T dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    const T squared = dx * dx + dy * dy + dz * dz;
    // The gradient of a norm at zero is undefined; joints never coincide in a fit
    // that starts from a hand, but guard the derivative anyway.
    const T norm = squared > T(1e-12) ? sqrt(squared) : T(1e-6);
    r[0] = T(w) * (norm / scale[0] - T(length));
    return true;
  }
};

struct Shape {
  Vec3 offset;  // the model's joint - wrist, camera axes, at the template's size
  double w;
  template <typename T>
  bool operator()(const T* joint, const T* wrist, const T* scale, T* r) const {
    for (int i = 0; i < 3; ++i) r[i] = T(w) * ((joint[i] - wrist[i]) / scale[0] - T(offset[i]));
    return true;
  }
};

// The hand-size prior: log of the track's scale, over its relative sigma.
struct ScalePrior {
  double w;
  template <typename T>
  bool operator()(const T* scale, T* r) const {
    r[0] = T(w) * log(scale[0]);
    return true;
  }
};

struct Acceleration {
  double w;
  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, const T* scale, T* r) const {
    for (int i = 0; i < 3; ++i) r[i] = T(w) * (a[i] - T(2) * b[i] + c[i]) / scale[0];
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

double TurnDeg(const Mat3& a, const Mat3& b) {
  return Eigen::AngleAxisd(Mat3(a.transpose() * b)).angle() * 180 / M_PI;
}

// Poses that turn more than `max_turn_deg` from most of the poses within
// `kFlipWindow` frames of them: the mirror-pose ambiguity of a nearly flat
// hand, where PnP's best pose flips for a frame (02_cups: wrist depth 72 ->
// 23 -> 62 cm, turned 175 degrees). Returns how many were dropped.
constexpr int kFlipWindow = 5;
int DropFlippedPoses(std::vector<std::optional<HandPose>>& poses, double max_turn_deg) {
  const int n = static_cast<int>(poses.size());
  std::vector<bool> flipped(poses.size(), false);
  for (int f = 0; f < n; ++f) {
    if (!poses[f]) continue;
    int agree = 0, disagree = 0;
    for (int g = std::max(0, f - kFlipWindow); g <= std::min(n - 1, f + kFlipWindow); ++g) {
      if (g == f || !poses[g]) continue;
      (TurnDeg(poses[f]->R, poses[g]->R) > max_turn_deg ? disagree : agree) += 1;
    }
    flipped[f] = disagree > agree;
  }
  // Poses that all disagree (two frames, say) give no majority: keep them.
  bool any_kept = false;
  for (int f = 0; f < n; ++f) any_kept = any_kept || (poses[f] && !flipped[f]);
  if (!any_kept) return 0;
  int dropped = 0;
  for (int f = 0; f < n; ++f) {
    if (flipped[f]) {
      poses[f].reset();
      ++dropped;
    }
  }
  return dropped;
}

// PnP per frame (flips dropped, and with `drop_mirrored` the poses of
// frames whose 3D hand is mirrored, hands/hand_outliers.h); frames without
// a pose (gaps, flips, frames PnP could not place) interpolated between the
// nearest posed ones.
// Returns false when no frame has a pose. `size` scales the model's
// landmarks (and so the PnP poses' translation) to the template's size.
bool Initialise(const Track& track, const Mat3& K, double size, double max_turn_deg,
                bool drop_mirrored, FittedTrack& out, std::vector<std::optional<HandPose>>& poses) {
  const size_t n = track.frames.size();
  poses.assign(n, std::nullopt);
  out.joints.assign(n, Joints{});
  out.pnp_joints.assign(n, Joints{});
  out.filled.assign(n, true);
  out.has_pnp.assign(n, false);
  for (size_t f = 0; f < n; ++f) {
    out.filled[f] = !track.frames[f];
    if (!track.frames[f]) continue;
    poses[f] = SolveHandPose(*track.frames[f], K);
    if (!poses[f]) continue;
    // Scaling the landmarks scales the pose's translation: same projection.
    for (auto& j : poses[f]->joints) j *= size;
    out.pnp_joints[f] = poses[f]->joints;
  }
  // A mirrored 3D hand's pose is turned over: its frame keeps its keypoints.
  const std::vector<bool> mirrored =
      drop_mirrored ? MirroredFrames(track) : std::vector<bool>(n, false);
  for (size_t f = 0; f < n; ++f) {
    if (!mirrored[f] || !poses[f]) continue;
    poses[f].reset();
    ++out.mirrored_poses;
  }
  out.flipped_poses = DropFlippedPoses(poses, max_turn_deg);
  std::vector<int> known;
  for (size_t f = 0; f < n; ++f) {
    if (!poses[f]) continue;
    out.joints[f] = poses[f]->joints;
    out.has_pnp[f] = true;
    known.push_back(static_cast<int>(f));
  }
  if (known.empty()) return false;
  for (size_t f = 0; f < n; ++f) {
    if (poses[f]) continue;
    const auto next = std::lower_bound(known.begin(), known.end(), static_cast<int>(f));
    const int b = next == known.end() ? known.back() : *next;
    const int a = next == known.begin() ? known.front() : *(next - 1);
    const double s = a == b ? 0.0 : (static_cast<double>(f) - a) / (b - a);
    for (int j = 0; j < kJoints; ++j)
      out.joints[f][j] = (1 - s) * out.joints[a][j] + s * out.joints[b][j];
  }
  return true;
}

void AddReprojection(ceres::Problem& problem, const HandObservation& o, const Mat3& K,
                     double sigma_px, const FitConfig& c, Joints& x) {
  for (int j = 0; j < kJoints; ++j) {
    if (o.confidence[j] <= 0) continue;
    const Reprojection r{o.uv[j].x(),
                         o.uv[j].y(),
                         K(0, 0),
                         K(1, 1),
                         K(0, 2),
                         K(1, 2),
                         std::sqrt(o.confidence[j]) / sigma_px};
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<Reprojection, 2, 3>(new Reprojection(r)),
        new ceres::HuberLoss(c.huber), x[j].data());
  }
}

void AddShape(ceres::Problem& problem, const HandObservation& o, const HandPose& pose, double size,
              const FitConfig& c, Joints& x, double* scale) {
  for (int j = 1; j < kJoints; ++j) {
    const Shape s{size * (pose.R * (o.world[j] - o.world[0])), 1.0 / c.shape_sigma_m};
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Shape, 3, 3, 3, 1>(new Shape(s)),
                             new ceres::HuberLoss(c.huber), x[j].data(), x[0].data(), scale);
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

// HOT3D P0003's hand at rest (see the header), mm, SkeletonLinks() order.
constexpr double kTemplateLinksMm[kJoints] = {
    52.04, 32.67, 33.84, 20.75,  // wrist - thumb CMC - MCP - IP - tip
    99.94, 36.99, 26.01, 20.83,  // wrist - index MCP - PIP - DIP - tip
    96.28, 41.37, 28.35, 23.55,  // middle
    90.40, 38.74, 26.98, 23.24,  // ring
    84.78, 29.34, 20.40, 20.30,  // little
    61.59};                      // index MCP - little MCP

double SumOfBones(const std::vector<double>& links) {
  double sum = 0;
  for (int k = 0; k + 1 < kJoints; ++k) sum += links[k];
  return sum;
}

}  // namespace

std::vector<double> TemplateLinkLengths(double hand_length_m) {
  std::vector<double> links(std::begin(kTemplateLinksMm), std::end(kTemplateLinksMm));
  const double own = HandLength(links);
  for (double& l : links) l *= hand_length_m / own;
  return links;
}

double HandLength(const std::vector<double>& link_length) {
  // The links to joints 9 (middle base), 10, 11, 12 (middle tip).
  return link_length[8] + link_length[9] + link_length[10] + link_length[11];
}

std::vector<std::pair<int, int>> SkeletonLinks() {
  std::vector<std::pair<int, int>> links;
  for (int j = 1; j < kJoints; ++j) links.emplace_back(j, kParent[j]);
  links.emplace_back(17, 5);  // across the palm
  return links;
}

namespace {

// One fit of the frames `track` observes (the header's problem).
FittedTrack FitObserved(const Track& track, const Mat3& K, double fps, const FitConfig& c) {
  const auto start = std::chrono::steady_clock::now();
  FittedTrack out;
  out.side = track.side;
  out.first_frame = track.first_frame;
  out.observations = track.frames;
  const std::vector<std::pair<int, int>> links = SkeletonLinks();
  std::vector<double> model_links;  // the landmark model's medians
  for (const auto& [a, b] : links) {
    std::vector<double> lengths;
    for (const auto& o : track.frames) {
      if (o) lengths.push_back((o->world[a] - o->world[b]).norm());
    }
    model_links.push_back(Median(lengths));
  }
  out.model_hand_length_m = HandLength(model_links);
  out.size_prior = c.size_prior == "adult";
  // The links at scale 1, and the factor from the model's size to theirs.
  const std::vector<double> base =
      out.size_prior ? TemplateLinkLengths(c.hand_length_m) : model_links;
  const double size = out.size_prior ? SumOfBones(base) / SumOfBones(model_links) : 1.0;
  std::vector<std::optional<HandPose>> poses;
  if (!Initialise(track, K, size, c.max_pnp_turn_deg, c.max_untrusted_run > 0, out, poses)) {
    out.joints.clear();
    return out;
  }
  const size_t n = out.joints.size();
  out.untrusted = track.untrusted;
  out.untrusted.resize(n, false);
  double scale = 1;
  ceres::Problem problem;
  const double sigma_px = c.reprojection_sigma * ImageSize(track);
  for (size_t f = 0; f < n; ++f) {
    if (track.frames[f]) AddReprojection(problem, *track.frames[f], K, sigma_px, c, out.joints[f]);
    if (poses[f] && c.world_prior) {
      AddShape(problem, *track.frames[f], *poses[f], size, c, out.joints[f], &scale);
    }
    for (size_t k = 0; k < links.size(); ++k) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Link, 1, 3, 3, 1>(
                                   new Link{1.0 / c.bone_sigma_m, base[k]}),
                               nullptr, out.joints[f][links[k].first].data(),
                               out.joints[f][links[k].second].data(), &scale);
    }
  }
  if (out.size_prior) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ScalePrior, 1, 1>(
                                 new ScalePrior{1.0 / c.hand_length_sigma}),
                             nullptr, &scale);
    problem.SetParameterLowerBound(&scale, 0, 0.2);
    problem.SetParameterUpperBound(&scale, 0, 5.0);
  } else {
    problem.SetParameterBlockConstant(&scale);
  }
  const double accel_w = 1.0 / (c.acceleration_sigma_ms2 / (fps * fps));
  for (size_t f = 1; f + 1 < n; ++f) {
    for (int j = 0; j < kJoints; ++j) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<Acceleration, 3, 3, 3, 3, 1>(new Acceleration{accel_w}),
          nullptr, out.joints[f - 1][j].data(), out.joints[f][j].data(),
          out.joints[f + 1][j].data(), &scale);
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
  out.scale = scale;
  out.link_length = base;
  for (double& l : out.link_length) l *= scale;
  out.reprojection_rms_px = ReprojectionRms(track, out, K);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace

FittedTrack FitTrack(const Track& track, const Mat3& K, double fps, const FitConfig& c) {
  FittedTrack fit = FitObserved(track, K, fps, c);
  if (fit.joints.empty()) return fit;
  const std::vector<bool> drop = UntrustedFrames(fit.joints, c.max_wrist_speed_m_s / fps,
                                                 c.max_wrist_turn_deg_s / fps, c.max_untrusted_run);
  const int dropped = static_cast<int>(std::count(drop.begin(), drop.end(), true));
  if (dropped == 0) return fit;
  const Track kept = WithoutFrames(track, drop);
  FittedTrack refit = kept.frames.empty() ? FittedTrack{} : FitObserved(kept, K, fps, c);
  if (refit.joints.empty()) return fit;
  refit.untrusted_frames = dropped;  // filled, or cut off at the track's ends
  refit.seconds += fit.seconds;
  refit.iterations += fit.iterations;
  return refit;
}

}  // namespace doasido::hands
