// The centroids of seed appendix "Hand-Object Alignment": the visible-hand
// centroid on the hand mesh (one ray per hand-mask pixel, first hits
// averaged), the same pixels' point-map centroid, and the object's
// point-map centroid over its mask.
#pragma once

#include <opencv2/core.hpp>

#include "core/geometry.h"
#include "recon/bundle/bundle.h"
#include "recon/ray_caster.h"

namespace doasido::recon {

// Sums over the pixels whose ray struck the hand mesh AND whose point-map
// value is valid, so that both centroids average the same pixels.
struct VisibleHand {
  Vec3 mesh_sum = Vec3::Zero();  // first hits on the hand mesh (hand-mesh scale)
  Vec3 map_sum = Vec3::Zero();   // point-map values at those pixels (point-map scale)
  int rays = 0;                  // mask pixels tried
  int hits = 0;                  // pixels counted in the sums

  Vec3 MeshCentroid() const { return mesh_sum / hits; }  // c_hand^H; requires hits > 0
  Vec3 MapCentroid() const { return map_sum / hits; }    // c_hand^M; requires hits > 0
  VisibleHand& operator+=(const VisibleHand& o);
};

// Camera-frame point map of frame t: ClipBundle::points when present, else
// the depth unprojected through K (CV_32FC3; invalid depth becomes NaN).
cv::Mat PointMapAt(const ClipBundle& bundle, int t);

// Whether a point-map value is usable: finite with z > 0.
bool ValidPoint(const cv::Vec3f& p);

// One ray per non-zero pixel of `mask` from the camera centre through the
// pixel centre (K^-1 [u v 1]) onto `hand` (camera frame).
VisibleHand CastHandMask(const RayCaster& hand, const Mat3& K, const cv::Mat& mask,
                         const cv::Mat& points);

// Mean point-map value over the valid pixels of `mask` (c_obj^M); `count`
// receives the number of pixels averaged (0: the result is NaN).
Vec3 MaskCentroid(const cv::Mat& mask, const cv::Mat& points, int* count);

}  // namespace doasido::recon
