#include "objects/object_track_fit.h"

#include <algorithm>

#include "objects/ceres_geometry.h"

namespace doasido::objects {
namespace {

struct AccelerationResidual {
  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, T* r) const {
    for (int k = 0; k < 3; ++k) r[k] = (c[k] - T(2) * b[k] + a[k]) * T(weight);
    return true;
  }
  double weight;  // fps² / sigma
};

// The rotation vector of R(a)ᵀ R(b): the turn from one frame to the next.
template <typename T>
void RelativeTurn(const T* a, const T* b, T* out) {
  T Ra[9], Rb[9], Rr[9];
  ceres::AngleAxisToRotationMatrix(a, Ra);  // column major
  ceres::AngleAxisToRotationMatrix(b, Rb);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      T s = T(0);
      for (int k = 0; k < 3; ++k) s += Ra[i * 3 + k] * Rb[j * 3 + k];  // (Raᵀ Rb)(i,j)
      Rr[j * 3 + i] = s;
    }
  }
  ceres::RotationMatrixToAngleAxis(Rr, out);
}

struct AngularAccelerationResidual {
  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, T* r) const {
    T w1[3], w2[3];
    RelativeTurn(a, b, w1);
    RelativeTurn(b, c, w2);
    for (int k = 0; k < 3; ++k) r[k] = (w2[k] - w1[k]) * T(weight);
    return true;
  }
  double weight;
};

// The keypoints' image size: their bounding box's diagonal, pixels.
double ImageSize(const BoxKeypoints& k) {
  Vec2 lo = k[0], hi = k[0];
  for (const Vec2& p : k) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return std::max((hi - lo).norm(), 1.0);
}

}  // namespace

std::vector<Pose> FitTrackPoses(const std::vector<TrackFrame>& frames, const Vec3& size,
                                const Mat3& K, double fps, const ObjectFitConfig& config) {
  const int n = static_cast<int>(frames.size());
  std::vector<Vec3> aa(n), t(n);
  for (int k = 0; k < n; ++k) {
    aa[k] = AngleAxisOf(frames[k].start.R());
    t[k] = frames[k].start.t;
  }
  ceres::Problem problem;
  for (int k = 0; k < n; ++k) {
    problem.AddParameterBlock(aa[k].data(), 3);
    problem.AddParameterBlock(t[k].data(), 3);
    if (!frames[k].keypoints) continue;
    const BoxKeypoints& kp = *frames[k].keypoints;
    const double sigma = config.reprojection_sigma * ImageSize(kp);
    auto add = [&](const Vec3& x, const Vec2& uv) {
      problem.AddResidualBlock(PointResidual::Create(x, uv, K, sigma),
                               new ceres::HuberLoss(config.huber), aa[k].data(), t[k].data());
    };
    if (frames[k].axis_only) {
      add(Vec3::Zero(), kp[0]);
      add(Vec3(0, size.y() / 2, 0), TopFaceCentre(kp));
      add(Vec3(0, -size.y() / 2, 0), BottomFaceCentre(kp));
    } else {
      for (int i = 0; i < kBoxKeypoints; ++i) add(BoxCorner(i).cwiseProduct(size) / 2, kp[i]);
    }
  }
  const double fps2 = fps * fps;
  for (int k = 1; k + 1 < n; ++k) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<AccelerationResidual, 3, 3, 3, 3>(
            new AccelerationResidual{fps2 / config.acceleration_sigma_ms2}),
        nullptr, t[k - 1].data(), t[k].data(), t[k + 1].data());
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<AngularAccelerationResidual, 3, 3, 3, 3>(
            new AngularAccelerationResidual{fps2 / config.angular_acceleration_sigma}),
        nullptr, aa[k - 1].data(), aa[k].data(), aa[k + 1].data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = config.max_iterations;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  std::vector<Pose> out(n);
  for (int k = 0; k < n; ++k) {
    out[k] = {Quat(RotationOf(aa[k])), t[k]};
  }
  return out;
}

}  // namespace doasido::objects
