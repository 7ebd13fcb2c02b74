// Synthetic sequences for the guided object tracker (recon/track/object_tracker.h)
// with exact answers: a mug (its handle breaks the symmetry of a 180-degree
// turn about its axis) moving and turning in front of a pinhole camera, at
// rest for some frames and turning fast for others; its true masks
// (rendered, with a hand-sized occluder cut out of some frames); followed
// points (the true motion of surface points plus pixel noise); and the
// stand-in object model, a Gaussian-mixture flow whose modes per frame are
// the true pose off by the estimator's error, its symmetric flip, and
// clutter poses scattered around it. Occluded frames make the model less
// sure: the true mode loses weight, the error grows.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "core/geometry.h"
#include "core/mesh.h"
#include "recon/track/adaptive_guidance.h"
#include "recon/track/gaussian_mixture_flow.h"

namespace doasido::synth {

struct TrackingSceneOptions {
  int frames = 25;
  int width = 160, height = 120;
  double focal = 220;
  int shape_dim = 4;
  double fast_turn_deg = 10;    // per frame during fast segments
  double slow_turn_deg = 1;     // per frame otherwise
  double mode_sigma = 0.004;    // spread of each mode (every coordinate)
  double pose_error = 0.003;    // the true mode's offset from the truth (translation, m)
  double flip_weight = 0.35;    // relative to the true mode's 1
  int clutter_modes = 3;        // each of weight clutter_weight
  double clutter_weight = 0.1;
  double occluded_share = 0.25; // frames with an occluder
  double track_noise_px = 0.5;
};

struct TrackingScene {
  TriMesh mesh;                      // object-local metres
  Camera camera;
  std::vector<Pose> truth;           // object-to-camera per frame
  std::vector<cv::Mat> masks;        // CV_8U, 255 = visible object
  std::vector<cv::Mat> hand_masks;   // CV_8U, 255 = the occluding hand (all 0 when none)
  std::vector<bool> occluded;
  std::unique_ptr<recon::GaussianMixtureFlow> model;
  // Where points of frame k are in frame k + 1 (the true motion of the
  // nearest projected surface point, plus noise).
  recon::PointFollower follow;
};

TrackingScene MakeTrackingScene(std::uint64_t seed, const TrackingSceneOptions& options = {});

}  // namespace doasido::synth
