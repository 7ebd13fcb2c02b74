// Pose guidance strength from the object's own motion (seed appendix,
// "Adaptive Guidance"): for each pair of consecutive frames, points inside
// the object mask of the first frame are followed to the second (the
// bundle's point tracks, else OpenCV's pyramidal Lucas-Kanade:
// recon/lucas_kanade_tracks.h); those that land inside the next mask are
// kept; a 2D rigid transform fitted to them in closed form (SVD) gives the
// in-plane rotation dtheta_k, and
//
//   alpha_p(k) = max(floor, offset - slope |dtheta_k|)
//
// with the seed's 0.1, 0.7 and 0.09. We read dtheta in degrees: in radians
// |dtheta| would have to exceed 6.7 rad (more than a turn between two
// frames) for the floor to matter, so the formula would be a constant 0.7
// in practice. At 0.09 per degree, alpha_p falls from 0.7 at rest to the
// floor at 6.7 degrees per frame. Frame 0 has no previous pose: alpha_p = 0.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "core/config.h"
#include "core/geometry.h"
#include "recon/bundle/bundle.h"

namespace doasido::recon {

struct AdaptiveGuidanceConfig {
  int points = 20;          // points drawn inside each frame's mask (seed)
  double floor = 0.1;       // alpha_p never goes below this (seed)
  double offset = 0.7;      // alpha_p at rest (seed)
  double slope_per_degree = 0.09;  // (seed)
  int min_points = 3;       // fewer kept points: the pair has no estimate
  double fallback = 0.4;    // alpha_p of a pair without an estimate
  std::uint64_t seed = 0;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(AdaptiveGuidanceConfig, points, floor, offset,
                                                slope_per_degree, min_points, fallback, seed)

void CheckConfig(const AdaptiveGuidanceConfig& c, const std::string& section);

// A 2D rigid motion b ~ R(angle) a + t.
struct RigidMotion2D {
  double angle_deg = 0;   // counter-clockwise in image coordinates (y down: clockwise on screen)
  Vec2 translation = Vec2::Zero();
};

// Least-squares rotation and translation taking `a` to `b` (same size, at
// least 2 distinct points), in closed form through the SVD of the
// cross-covariance, reflections excluded.
RigidMotion2D FitRigid2D(const std::vector<Vec2>& a, const std::vector<Vec2>& b);

// The seed's clamped affine function of |dtheta| in degrees.
double PoseGuidance(double dtheta_deg, const AdaptiveGuidanceConfig& c);

// Where a point of frame k is in frame k + 1 (nullopt: lost).
struct PointFollow {
  Vec2 from, to;
  bool found = false;
};

// Follows points from one frame to the next: given the frame index k and
// points in frame k, returns where each is in frame k + 1.
using PointFollower = std::function<std::vector<PointFollow>(int, const std::vector<Vec2>&)>;

// Follows points with a bundle's point tracks (TAPIR, BootsTAPIR): a pixel
// of frame k takes the nearest track visible in frames k and k + 1 within
// `radius_px`, and moves as that track does; farther from every such track
// it is lost.
PointFollower FollowPointTracks(const PointTracks& tracks, double radius_px);

struct GuidanceEstimate {
  std::vector<double> alpha_p;    // per frame; [0] = 0
  std::vector<double> dtheta_deg; // per frame (NaN where no estimate); [0] = 0
  std::vector<int> points_kept;   // per frame; [0] = 0
};

// alpha_p for every frame of a clip with `masks` (CV_8U, nonzero = object),
// drawing config.points pixels of mask k (seeded) and following them with
// `follow`.
GuidanceEstimate EstimatePoseGuidance(const std::vector<cv::Mat>& masks,
                                      const PointFollower& follow,
                                      const AdaptiveGuidanceConfig& config);

}  // namespace doasido::recon
