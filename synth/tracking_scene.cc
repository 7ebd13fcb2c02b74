#include "synth/tracking_scene.h"

#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

#include "recon/recon_metrics.h"
#include "recon/track/silhouette.h"
#include "synth/objects.h"

namespace doasido::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

Quat SmallRotation(double radians, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  const Vec3 axis = Vec3(normal(rng), normal(rng), normal(rng)).normalized();
  return Quat(Eigen::AngleAxisd(radians, axis));
}

// The truth: upright mug, a random walk of the position, turns about axes
// near the optical axis (what a 2D rigid fit can see), fast in runs.
std::vector<Pose> Trajectory(const TrackingSceneOptions& o, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0, 1);
  Pose pose;
  pose.q = Quat(Eigen::AngleAxisd(-kPi / 2, Vec3::UnitX())) *  // object z to camera -y
           Quat(Eigen::AngleAxisd(2 * kPi * uniform(rng), Vec3::UnitZ()));
  pose.t = Vec3(0.01 * normal(rng), 0.03, 0.42 + 0.03 * normal(rng));
  std::vector<Pose> out;
  bool fast = false;
  for (int k = 0; k < o.frames; ++k) {
    out.push_back(pose);
    if (uniform(rng) < (fast ? 0.3 : 0.2)) fast = !fast;
    const double turn = (fast ? o.fast_turn_deg : o.slow_turn_deg) * kDeg *
                        (uniform(rng) < 0.5 ? -1 : 1) * (0.7 + 0.6 * uniform(rng));
    const Vec3 axis = (Vec3::UnitZ() + 0.3 * Vec3(normal(rng), normal(rng), 0)).normalized();
    pose.q = (Quat(Eigen::AngleAxisd(turn, axis)) * pose.q).normalized();
    pose.t += 0.003 * Vec3(normal(rng), normal(rng), 0.5 * normal(rng));
  }
  return out;
}

Eigen::VectorXd State(const Eigen::VectorXd& shape, const Pose& pose, const Quat& hemisphere) {
  Pose p = pose;
  p.q = SameHemisphere(p.q, hemisphere);
  Eigen::VectorXd x(shape.size() + recon::kPoseDim);
  x << shape, recon::PoseBlock(p).transpose();
  return x;
}

recon::Mixture Modes(const TrackingSceneOptions& o, const Eigen::VectorXd& shape,
                     const Pose& truth, bool occluded, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  const double error = o.pose_error * (occluded ? 2 : 1);
  const double sigma = o.mode_sigma * (occluded ? 1.5 : 1);
  auto noisy = [&](const Pose& p) {
    return Pose{SmallRotation(error / 0.05, rng) * p.q,
                p.t + error * Vec3(normal(rng), normal(rng), normal(rng))};
  };
  const Pose flip{truth.q * Quat(Eigen::AngleAxisd(kPi, Vec3::UnitZ())), truth.t};
  recon::Mixture modes;
  modes.push_back({occluded ? 0.5 : 1.0, State(shape, noisy(truth), truth.q), sigma});
  modes.push_back({o.flip_weight, State(shape, noisy(flip), truth.q), sigma});
  for (int c = 0; c < o.clutter_modes; ++c) {
    const Pose clutter{Quat::UnitRandom(), truth.t + 0.03 * Vec3(normal(rng), normal(rng), normal(rng))};
    modes.push_back({o.clutter_weight, State(shape, clutter, truth.q), sigma * 2});
  }
  return modes;
}

// Cuts a hand-sized box out of the object's mask and returns the hand's mask.
cv::Mat CutOccluder(cv::Mat& mask, std::mt19937_64& rng) {
  cv::Mat hand(mask.size(), CV_8U, cv::Scalar(0));
  const cv::Rect box = cv::boundingRect(mask);
  if (box.empty()) return hand;
  std::uniform_real_distribution<double> uniform(0, 1);
  const int w = std::max(1, box.width / 2), h = std::max(1, box.height / 2);
  const cv::Rect cut(box.x + static_cast<int>(uniform(rng) * (box.width - w)),
                     box.y + static_cast<int>(uniform(rng) * (box.height - h)), w, h);
  const cv::Rect inside = cut & cv::Rect(0, 0, mask.cols, mask.rows);
  mask(inside).setTo(0);
  hand(inside).setTo(255);
  return hand;
}

}  // namespace

TrackingScene MakeTrackingScene(std::uint64_t seed, const TrackingSceneOptions& o) {
  std::mt19937_64 rng(seed * 7919 + 17);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0, 1);
  TrackingScene s;
  s.mesh = MakeMug(0.04, 0.09);
  s.camera = {.width = o.width, .height = o.height, .fx = o.focal, .fy = o.focal,
              .cx = o.width / 2.0, .cy = o.height / 2.0};
  s.truth = Trajectory(o, rng);
  const recon::SilhouetteRenderer renderer(s.mesh);
  Eigen::VectorXd shape(o.shape_dim);
  for (int i = 0; i < o.shape_dim; ++i) shape[i] = 0.5 * normal(rng);
  std::vector<recon::Mixture> frames;
  for (const Pose& truth : s.truth) {
    s.occluded.push_back(uniform(rng) < o.occluded_share);
    s.masks.push_back(renderer.Render(truth, s.camera));
    s.hand_masks.push_back(s.occluded.back() ? CutOccluder(s.masks.back(), rng)
                                             : cv::Mat(s.masks.back().size(), CV_8U, cv::Scalar(0)));
    frames.push_back(Modes(o, shape, truth, s.occluded.back(), rng));
  }
  s.model = std::make_unique<recon::GaussianMixtureFlow>(
      recon::FlowLayout{.shape_dim = o.shape_dim}, std::move(frames));

  const recon::Points3 surface = recon::SampleSurface(s.mesh, 400, seed);
  const auto truth = s.truth;
  const Camera camera = s.camera;
  const double noise_px = o.track_noise_px;
  auto noise_rng = std::make_shared<std::mt19937_64>(seed + 5);
  s.follow = [surface, truth, camera, noise_px, noise_rng](int k, const std::vector<Vec2>& points) {
    std::normal_distribution<double> noise(0, noise_px);
    std::vector<recon::PointFollow> out;
    for (const Vec2& p : points) {
      double best = 4.0;  // pixels: farther from every surface point is lost
      int nearest = -1;
      for (Eigen::Index i = 0; i < surface.rows(); ++i) {
        const double d = (camera.Project(truth[k] * Vec3(surface.row(i).transpose())) - p).norm();
        if (d < best) {
          best = d;
          nearest = static_cast<int>(i);
        }
      }
      recon::PointFollow f{p, p, nearest >= 0};
      if (f.found) {
        const Vec3 x = surface.row(nearest).transpose();
        f.to = p + camera.Project(truth[k + 1] * x) - camera.Project(truth[k] * x) +
               Vec2(noise(*noise_rng), noise(*noise_rng));
      }
      out.push_back(f);
    }
    return out;
  };
  return s;
}

}  // namespace doasido::synth
