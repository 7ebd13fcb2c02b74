// The silhouette of a mesh at a pose, seen by a pinhole camera: one ray per
// pixel (every `stride`-th pixel in both directions) cast with Embree
// (recon/ray_caster.h) into the mesh's own frame, so one scene serves every
// pose. Candidate selection (recon/track/pose_selection.h) ranks poses by the
// silhouette's IoU with the object mask.
#pragma once

#include <opencv2/core.hpp>

#include "core/geometry.h"
#include "core/mesh.h"
#include "recon/ray_caster.h"

namespace doasido::recon {

class SilhouetteRenderer {
 public:
  // `mesh` in object-local metres.
  explicit SilhouetteRenderer(const TriMesh& mesh);

  // CV_8U mask of camera.height x camera.width, 255 where a pixel's ray
  // meets the mesh placed at `pose` (object-to-camera). With stride > 1 the
  // pixels between samples copy the sample above-left of them.
  cv::Mat Render(const Pose& pose, const Camera& camera, int stride = 1) const;

  // Intersection over union of Render(pose) and `mask` (nonzero = object)
  // over the sampled pixels; 0 when both are empty. Pixels nonzero in
  // `occluders` (the hands' masks; may be empty) count for neither: the
  // object may or may not be behind them. Casts rays only inside the boxes
  // of the mask and of the projected mesh.
  double IoU(const Pose& pose, const Camera& camera, const cv::Mat& mask, int stride = 1,
             const cv::Mat& occluders = {}) const;

 private:
  // Whether the ray through pixel (u, v) meets the mesh at `pose`.
  bool Hits(const Pose& inverse, const Camera& camera, int u, int v) const;
  // Pixels the mesh at `pose` can cover: the box of its projected vertices
  // (the whole image when a vertex is behind the camera).
  cv::Rect Footprint(const Pose& pose, const Camera& camera) const;

  TriMesh mesh_;
  RayCaster caster_;
};

}  // namespace doasido::recon
