// Model-like corruption of exact ground truth, so that downstream stages can
// be tested against inputs that look like what the foundation models hand in
// while the true answer stays known.
//
// MoGe-like depth: MoGe predicts affine-invariant geometry whose metric scale
// is estimated per frame; the scale error dominates. Each frame's depth is
// multiplied by s_t = exp(g_t), g_t ~ N(0, scale_sigma) drawn independently
// per frame, then every pixel gets multiplicative noise
// (1 + N(0, pixel_sigma)); invalid pixels stay invalid.
//
// HaWoR-like hands: per-joint independent noise N(0, joint_sigma) on every
// coordinate, plus a per-frame rigid offset of the whole hand that follows
// an AR(1) process (x_t = rho x_{t-1} + N(0, jitter_sigma)), i.e. correlated
// jitter as seen in per-frame regressors; mesh vertices move with the rigid
// offset. A per-clip depth bias along the camera ray (N(0, depth_sigma))
// mimics the scale ambiguity of monocular hands.
//
// SAM 3D-like pose samples: per frame, N samples around the true pose, drawn
// from three modes: near-true (rotation N(0, near_rot_sigma) rad about a
// random axis, translation N(0, near_trans_sigma) m), symmetric flips (the
// true pose composed with a half turn about the object's local z or x axis,
// the ambiguity of symmetric objects, plus near-true noise), and scattered
// outliers (uniform random rotation, translation N(0, outlier_trans_sigma)).
// The scale is exp(N(0, scale_sigma)). Samples are drawn in mode order and
// shuffled when `shuffle` is set (the default), so the index says nothing
// about the mode.
#pragma once

#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "core/config.h"
#include "core/geometry.h"
#include "recon/bundle/bundle.h"

namespace doasido::synth {

struct DepthNoiseConfig {
  double scale_sigma = 0.05;
  double pixel_sigma = 0.01;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(DepthNoiseConfig, scale_sigma, pixel_sigma)

struct HandNoiseConfig {
  double joint_sigma = 0.006;   // m
  double jitter_sigma = 0.003;  // m
  double jitter_rho = 0.7;
  double depth_sigma = 0.02;  // m, per clip
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(HandNoiseConfig, joint_sigma, jitter_sigma,
                                                jitter_rho, depth_sigma)

struct CandidateConfig {
  int samples = 16;
  double near_fraction = 0.5;
  double flip_fraction = 0.25;  // the rest are outliers
  double near_rot_sigma = 0.06;
  double near_trans_sigma = 0.008;
  double outlier_trans_sigma = 0.08;
  double scale_sigma = 0.05;
  bool shuffle = true;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(CandidateConfig, samples, near_fraction,
                                                flip_fraction, near_rot_sigma, near_trans_sigma,
                                                outlier_trans_sigma, scale_sigma, shuffle)

// Scales each frame in place; returns the per-frame scale factors s_t.
std::vector<double> ApplyDepthNoise(std::vector<cv::Mat>& depth, const DepthNoiseConfig& cfg,
                                    std::mt19937_64& rng);

// Corrupts joints (and verts) in place.
void ApplyHandNoise(recon::HandTrack& hand, const HandNoiseConfig& cfg, std::mt19937_64& rng);

// Which mode a candidate came from.
enum class CandidateMode { kNear = 0, kFlip = 1, kOutlier = 2 };

// Pose samples per frame around `truth` (object -> camera). Flips turn about
// axes through `local_centre` (object-local), so a flipped object stays in
// place. `modes`, when given, receives the mode of every sample.
std::vector<std::vector<recon::PoseSample>> SamplePoseCandidates(
    const std::vector<Pose>& truth, const Vec3& local_centre, const CandidateConfig& cfg,
    std::mt19937_64& rng, std::vector<std::vector<CandidateMode>>* modes = nullptr);

}  // namespace doasido::synth
