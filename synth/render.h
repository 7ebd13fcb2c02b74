// Renders one frame of the synthetic world: a textured table and back wall,
// one object and up to two hands, through a pinhole camera, with Lambert
// shading. Besides the colour image it returns the exact z-buffer (depth and
// the visible surface per pixel), from which masks and point maps follow.
#pragma once

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>

#include "core/geometry.h"
#include "core/mesh.h"
#include "synth/hand_model.h"
#include "video/mesh_rasterizer.h"
#include "synth/texture.h"

namespace doasido::synth {

// Surface ids in video::RasterTarget::surface.
enum SurfaceId : std::uint8_t {
  kSurfaceNone = 0,
  kSurfaceTable = 1,
  kSurfaceWall = 2,
  kSurfaceObject = 3,
  kSurfaceHandLeft = 4,
  kSurfaceHandRight = 5,
};

// The static world: world frame has +z up and the table top at z = 0; the
// back wall is the plane y = wall_y facing -y.
struct World {
  TextureStyle style;
  Vec3 light_dir = Vec3(-0.3, -0.5, 0.8).normalized();  // towards the light, world frame
  double ambient = 0.4;
  double diffuse = 0.7;
  double wall_y = 0.8;
  double table_half = 1.5;  // half extent of the table square
};

// Everything that changes per frame, in world coordinates.
struct FrameState {
  Camera camera;
  Pose camera_from_world;
  Pose object_pose;  // object-local -> world
  bool object_present = true;
  std::array<std::optional<PosedHand>, 2> hands;  // indexed by Side
  std::array<Pose, 2> hand_wrist;                 // wrist poses (for skin texture coordinates)
};

struct RenderedFrame {
  cv::Mat bgr;          // CV_8UC3
  video::RasterTarget raster;  // depth (camera z, metres), surface ids, faces
};

// The rendered table and wall of one view, reused while the camera stays
// put (the background is static, so its raster and shading depend only on
// the world and the camera).
struct BackgroundCache {
  bool valid = false;
  Camera camera;
  Pose camera_from_world;
  RenderedFrame frame;
};

// Renders `state`. `object_mesh` is object-local. With a `cache` (one per
// world), the background is drawn once per camera view; the result is
// identical to rendering without it.
RenderedFrame RenderFrame(const World& world, const TriMesh& object_mesh, const FrameState& state,
                          const video::RasterOptions& options = {},
                          BackgroundCache* cache = nullptr);

// Adds zero-mean Gaussian sensor noise (sigma in 8-bit levels), reproducibly.
void AddSensorNoise(cv::Mat& bgr, double sigma, std::uint64_t seed);

// 0/255 mask of pixels whose visible surface is `id`.
cv::Mat SurfaceMask(const video::RasterTarget& raster, std::uint8_t id);

// Camera-frame point map (CV_32FC3) from a depth map; NaN where depth is not
// finite.
cv::Mat DepthToPoints(const cv::Mat& depth, const Camera& camera);

// A camera at `eye` looking at `target` with world +z up (OpenCV axes:
// x right, y down, z forward); returns camera_from_world.
Pose LookAt(const Vec3& eye, const Vec3& target);

}  // namespace doasido::synth
