#include "synth/model_noise.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace doasido::synth {
namespace {

Vec3 RandomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3 v(n(rng), n(rng), n(rng));
  while (v.norm() < 1e-9) v = Vec3(n(rng), n(rng), n(rng));
  return v.normalized();
}

Quat SmallRotation(double sigma, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, sigma);
  return Quat(Eigen::AngleAxisd(n(rng), RandomUnit(rng)));
}

Quat UniformRotation(std::mt19937_64& rng) {
  // Shoemake's method.
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double u1 = u(rng), u2 = 2 * M_PI * u(rng), u3 = 2 * M_PI * u(rng);
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  return Quat(a * std::sin(u2), a * std::cos(u2), b * std::sin(u3), b * std::cos(u3));
}

}  // namespace

std::vector<double> ApplyDepthNoise(std::vector<cv::Mat>& depth, const DepthNoiseConfig& cfg,
                                    std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, cfg.scale_sigma), px(0.0, cfg.pixel_sigma);
  std::vector<double> scales;
  for (cv::Mat& d : depth) {
    const double s = std::exp(g(rng));
    scales.push_back(s);
    for (int y = 0; y < d.rows; ++y) {
      float* row = d.ptr<float>(y);
      for (int x = 0; x < d.cols; ++x) {
        if (!std::isfinite(row[x]) || row[x] <= 0) continue;
        row[x] = static_cast<float>(row[x] * s * (1 + px(rng)));
      }
    }
  }
  return scales;
}

void ApplyHandNoise(recon::HandTrack& hand, const HandNoiseConfig& cfg, std::mt19937_64& rng) {
  std::normal_distribution<double> joint(0.0, cfg.joint_sigma), jit(0.0, cfg.jitter_sigma),
      depth(0.0, cfg.depth_sigma);
  const double bias = depth(rng);
  Vec3 offset = Vec3::Zero();
  for (size_t t = 0; t < hand.joints.size(); ++t) {
    offset = cfg.jitter_rho * offset + Vec3(jit(rng), jit(rng), jit(rng));
    const Vec3 wrist = hand.joints[t].row(0).transpose();
    const Vec3 ray = wrist.norm() > 1e-9 ? Vec3(wrist.normalized()) : Vec3::UnitZ();
    const Vec3 shift = offset + bias * ray;
    for (int j = 0; j < 21; ++j) {
      hand.joints[t].row(j) += (shift + Vec3(joint(rng), joint(rng), joint(rng))).transpose();
    }
    if (t < hand.verts.size()) hand.verts[t].rowwise() += shift.transpose();
  }
}

std::vector<std::vector<recon::PoseSample>> SamplePoseCandidates(
    const std::vector<Pose>& truth, const Vec3& local_centre, const CandidateConfig& cfg,
    std::mt19937_64& rng, std::vector<std::vector<CandidateMode>>* modes) {
  std::normal_distribution<double> trans(0.0, cfg.near_trans_sigma),
      far(0.0, cfg.outlier_trans_sigma), scale(0.0, cfg.scale_sigma);
  const int n_near = static_cast<int>(std::lround(cfg.samples * cfg.near_fraction));
  const int n_flip = std::min(cfg.samples - n_near,
                              static_cast<int>(std::lround(cfg.samples * cfg.flip_fraction)));
  std::vector<std::vector<recon::PoseSample>> out;
  if (modes) modes->clear();
  std::uniform_int_distribution<int> coin(0, 1);
  for (const Pose& p : truth) {
    std::vector<recon::PoseSample> samples;
    std::vector<CandidateMode> m;
    for (int i = 0; i < cfg.samples; ++i) {
      Pose s = p;
      CandidateMode mode = CandidateMode::kNear;
      if (i < n_near) {
        s.q = SmallRotation(cfg.near_rot_sigma, rng) * p.q;
        s.t = p.t + Vec3(trans(rng), trans(rng), trans(rng));
      } else if (i < n_near + n_flip) {
        mode = CandidateMode::kFlip;
        const Vec3 axis = coin(rng) ? Vec3::UnitZ() : Vec3::UnitX();
        const Quat flip(Eigen::AngleAxisd(M_PI, axis));
        const Quat noise = SmallRotation(cfg.near_rot_sigma, rng);
        s.q = noise * p.q * flip;
        const Vec3 world_centre = p * local_centre;
        s.t = world_centre - s.q * local_centre + Vec3(trans(rng), trans(rng), trans(rng));
      } else {
        mode = CandidateMode::kOutlier;
        s.q = UniformRotation(rng);
        s.t = p.t + Vec3(far(rng), far(rng), far(rng));
      }
      s.q.normalize();
      samples.push_back({s, std::exp(scale(rng))});
      m.push_back(mode);
    }
    if (cfg.shuffle) {
      std::vector<int> order(samples.size());
      std::iota(order.begin(), order.end(), 0);
      std::shuffle(order.begin(), order.end(), rng);
      std::vector<recon::PoseSample> s2;
      std::vector<CandidateMode> m2;
      for (int k : order) {
        s2.push_back(samples[k]);
        m2.push_back(m[k]);
      }
      samples.swap(s2);
      m.swap(m2);
    }
    out.push_back(std::move(samples));
    if (modes) modes->push_back(std::move(m));
  }
  return out;
}

}  // namespace doasido::synth
