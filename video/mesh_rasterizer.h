// CPU z-buffer rasterisation of triangle meshes given in camera coordinates
// (OpenCV axes, metres) through a pinhole camera. Pixel centres are at
// integer coordinates; a pixel is covered when its centre lies inside the
// projected triangle (edges included). Depth is the camera-frame z of the
// visible surface, interpolated perspective-correctly (1/z is affine in
// screen space), so it equals the exact ray-plane depth of the triangle.
// Geometry in front of the near plane is clipped, so large planes that pass
// behind the camera render correctly.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

#include "core/geometry.h"
#include "core/mesh.h"

namespace doasido::video {

struct RasterTarget {
  cv::Mat depth;    // CV_32F (H,W), +inf where nothing was drawn
  cv::Mat surface;  // CV_8U (H,W), id of the visible surface, 0 = none
  cv::Mat face;     // CV_32S (H,W), face index within that surface's mesh, -1 = none

  // Allocates (when needed) and clears to empty.
  void Reset(int width, int height);
};

struct RasterOptions {
  double near = 0.01;      // metres
  bool cull_back = false;  // skip faces whose ccw side looks away from the camera
};

// Draws `mesh_cam` (camera frame) with surface id `id` (1-255) into `target`,
// keeping the nearest surface per pixel. Returns the number of pixels written.
std::int64_t Rasterize(const TriMesh& mesh_cam, const Camera& camera, std::uint8_t id,
                       RasterTarget& target, const RasterOptions& options = {});

// Reference peer for benchmarks and tests: for every pixel, every triangle
// (no bounding boxes, no incremental edge functions). Same coverage and depth
// rule as Rasterize, without near-plane clipping (all vertices must be in
// front of the camera).
std::int64_t RasterizeBruteForce(const TriMesh& mesh_cam, const Camera& camera, std::uint8_t id,
                                 RasterTarget& target);

}  // namespace doasido::video
