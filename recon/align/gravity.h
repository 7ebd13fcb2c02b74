// Gravity for the reconstruction (seed §3.1 uses GeoCalib): the bundle's
// up vectors (gravity.npz, camera frame) when present, else a RANSAC plane
// fit of the support surface in the point map: the largest plane that has
// the hands (else the camera) on its upper side, found among the few
// largest planes of the frame with hand and object pixels left out.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "core/config.h"
#include "core/geometry.h"
#include "recon/bundle/bundle.h"

namespace doasido::recon {

struct GravityConfig {
  bool use_bundle_up = true;       // false: always fit the plane
  int ransac_iterations = 400;
  double inlier_distance = 0.01;   // point-map units (m for a metric map)
  int max_planes = 3;              // planes peeled off before choosing
  int stride = 4;                  // use every stride-th pixel in both directions
  double min_inlier_share = 0.05;  // of the sampled points, for a plane to count
  std::uint64_t seed = 1;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(GravityConfig, use_bundle_up, ransac_iterations,
                                                inlier_distance, max_planes, stride,
                                                min_inlier_share, seed)
void CheckConfig(const GravityConfig& c, const std::string& section);

// Sources of the up direction (GravityEstimate::source).
inline constexpr const char* kGravityFromBundle = "bundle_up";
inline constexpr const char* kGravityFromPlane = "support_plane";
inline constexpr const char* kGravityFromCamera = "camera_minus_y";  // nothing else found

struct GravityEstimate {
  Vec3 up = Vec3(0, -1, 0);  // unit, camera frame
  std::string source = kGravityFromCamera;
  double inlier_share = 0;   // plane fit: inliers / sampled points; NaN for other sources
  int frame = -1;            // frame whose point map was fitted
  double spread_deg = 0;     // bundle up: RMS angle of the per-frame vectors to their mean
};

struct SupportPlane {
  Vec3 normal;         // unit, pointing to the hands' side
  double offset = 0;   // plane: normal . x + offset = 0
  double inlier_share = 0;
};

// Fits the support plane in one point map. `exclude` (CV_8U, may be empty)
// marks pixels to leave out (hands, object); `above` is a point that must
// lie on the plane's upper side (the hands' centroid, or the camera centre).
std::optional<SupportPlane> FitSupportPlane(const cv::Mat& points, const cv::Mat& exclude,
                                            const Vec3& above, const GravityConfig& config);

// The clip's up direction: the normalised mean of gravity_up when present
// (and use_bundle_up), else the support plane of the first frame with a
// plane, else the camera's -y.
GravityEstimate EstimateGravity(const ClipBundle& bundle, const GravityConfig& config);

// Rotation taking camera coordinates to a frame whose +z is `up` and whose
// x is the camera x made horizontal.
Mat3 UpToZ(const Vec3& up_camera);

}  // namespace doasido::recon
