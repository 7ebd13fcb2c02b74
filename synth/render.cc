#include "synth/render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "synth/objects.h"

namespace doasido::synth {
namespace {

Vec3 FaceNormal(const TriMesh& m, int f) {
  const Vec3 a = m.vertices.row(m.faces(f, 0)), b = m.vertices.row(m.faces(f, 1)),
             c = m.vertices.row(m.faces(f, 2));
  return (b - a).cross(c - a).normalized();
}

Vec3 ClosestOnSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 < 1e-18) return a;
  return a + std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) * ab;
}

std::uint8_t ToByte(double v) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(v * 255.0), 0L, 255L));
}

}  // namespace

Pose LookAt(const Vec3& eye, const Vec3& target) {
  const Vec3 z = (target - eye).normalized();
  Vec3 x = z.cross(Vec3::UnitZ());
  if (x.norm() < 1e-9) x = Vec3::UnitX();
  x.normalize();
  const Vec3 y = z.cross(x);
  Mat3 world_from_cam;
  world_from_cam.col(0) = x;
  world_from_cam.col(1) = y;
  world_from_cam.col(2) = z;
  Pose world_cam{Quat(world_from_cam), eye};
  return world_cam.Inverse();
}

namespace {

bool SameView(const BackgroundCache& c, const Camera& cam, const Pose& cw) {
  return c.valid && c.camera.width == cam.width && c.camera.height == cam.height &&
         c.camera.fx == cam.fx && c.camera.fy == cam.fy && c.camera.cx == cam.cx &&
         c.camera.cy == cam.cy && c.camera_from_world.q.coeffs() == cw.q.coeffs() &&
         c.camera_from_world.t == cw.t;
}

// The steps of RenderFrame.

// Lambert shading of a point `p` in camera coordinates, the light given in
// camera coordinates too; a surface seen from behind (a mug's interior) is
// lit as its other side.
struct Shader {
  const World& world;
  Vec3 light;

  cv::Vec3b operator()(const Vec3& n_in, const Vec3& p, const Rgb& albedo) const {
    Vec3 n = n_in;
    if (n.dot(p) > 0) n = -n;
    const Rgb c = albedo * (world.ambient + world.diffuse * std::max(0.0, n.dot(light)));
    return cv::Vec3b(ToByte(c.z()), ToByte(c.y()), ToByte(c.x()));
  }
};

// A deep copy of a frame's picture and rasters.
void CopyFrame(const RenderedFrame& from, RenderedFrame& to) {
  to.bgr = from.bgr.clone();
  to.raster.depth = from.raster.depth.clone();
  to.raster.surface = from.raster.surface.clone();
  to.raster.face = from.raster.face.clone();
}

// The table and the wall behind it, rasterised and shaded with their
// textures into a fresh frame.
void RenderBackground(const World& world, const Camera& cam, const Pose& cw,
                      const video::RasterOptions& options, const Shader& shade,
                      RenderedFrame& out) {
  const Pose wc = cw.Inverse();
  out.raster.Reset(cam.width, cam.height);
  TriMesh table = MakePlane(2 * world.table_half, world.wall_y + world.table_half);
  table = table.Transformed(
      cw * Pose{Quat::Identity(), Vec3(0, (world.wall_y - world.table_half) / 2, 0)});
  TriMesh wall = MakePlane(2 * world.table_half, 2.0);
  const Mat3 wall_rot = (Mat3() << 1, 0, 0, 0, 0, -1, 0, 1, 0).finished();  // +z -> -y
  wall = wall.Transformed(cw * Pose{Quat(wall_rot), Vec3(0, world.wall_y, 0.99)});
  video::Rasterize(table, cam, kSurfaceTable, out.raster, options);
  video::Rasterize(wall, cam, kSurfaceWall, out.raster, options);
  out.bgr.create(cam.height, cam.width, CV_8UC3);
  const Vec3 n_table = cw.R() * Vec3::UnitZ(), n_wall = cw.R() * -Vec3::UnitY();
  for (int y = 0; y < cam.height; ++y) {
    const float* drow = out.raster.depth.ptr<float>(y);
    const std::uint8_t* srow = out.raster.surface.ptr<std::uint8_t>(y);
    cv::Vec3b* crow = out.bgr.ptr<cv::Vec3b>(y);
    for (int x = 0; x < cam.width; ++x) {
      if (srow[x] == kSurfaceNone) {
        crow[x] = cv::Vec3b(0, 0, 0);
        continue;
      }
      const Vec3 p = cam.Unproject(x, y, drow[x]);
      const Vec3 w = wc * p;
      crow[x] = srow[x] == kSurfaceTable
                    ? shade(n_table, p, TableTexture(world.style, w.x(), w.y()))
                    : shade(n_wall, p, WallTexture(world.style, w.x(), w.z()));
    }
  }
}

// Shades the pixels the object and the hands (already rasterised, in
// camera coordinates) won: the object by its faces, a hand by the capsule
// under the pixel (smooth normals), each with its texture.
void ShadeForeground(const World& world, const FrameState& state, const TriMesh& object_cam,
                     const std::array<TriMesh, 2>& hand_cam, const Shader& shade,
                     RenderedFrame& out) {
  const Camera& cam = state.camera;
  const Pose& cw = state.camera_from_world;
  const Pose object_from_cam = (cw * state.object_pose).Inverse();
  std::array<Pose, 2> hand_from_cam = {(cw * state.hand_wrist[0]).Inverse(),
                                       (cw * state.hand_wrist[1]).Inverse()};
  for (int y = 0; y < cam.height; ++y) {
    const float* drow = out.raster.depth.ptr<float>(y);
    const std::uint8_t* srow = out.raster.surface.ptr<std::uint8_t>(y);
    const int* frow = out.raster.face.ptr<int>(y);
    cv::Vec3b* crow = out.bgr.ptr<cv::Vec3b>(y);
    for (int x = 0; x < cam.width; ++x) {
      const std::uint8_t id = srow[x];
      if (id < kSurfaceObject) continue;
      const Vec3 p = cam.Unproject(x, y, drow[x]);
      const int f = frow[x];
      if (id == kSurfaceObject) {
        crow[x] =
            shade(FaceNormal(object_cam, f), p, ObjectTexture(world.style, object_from_cam * p));
        continue;
      }
      const int s = id == kSurfaceHandLeft ? 0 : 1;
      const PosedHand& hand = *state.hands[s];
      const Capsule& c = hand.capsules[hand.capsule_of_face[f]];
      const Vec3 q = ClosestOnSegment(p, cw * c.a, cw * c.b);
      const Vec3 n =
          (p - q).norm() > 1e-9 ? Vec3((p - q).normalized()) : FaceNormal(hand_cam[s], f);
      crow[x] = shade(n, p, SkinTexture(world.style, hand_from_cam[s] * p));
    }
  }
}

}  // namespace

RenderedFrame RenderFrame(const World& world, const TriMesh& object_mesh, const FrameState& state,
                          const video::RasterOptions& options, BackgroundCache* cache) {
  const Camera& cam = state.camera;
  const Pose& cw = state.camera_from_world;
  const Shader shade{world, cw.R() * world.light_dir};
  RenderedFrame out;
  if (cache != nullptr && SameView(*cache, cam, cw)) {
    CopyFrame(cache->frame, out);
  } else {
    RenderBackground(world, cam, cw, options, shade, out);
    if (cache != nullptr) {
      cache->valid = true;
      cache->camera = cam;
      cache->camera_from_world = cw;
      CopyFrame(out, cache->frame);
    }
  }
  TriMesh object_cam;
  if (state.object_present) {
    object_cam = object_mesh.Transformed(cw * state.object_pose);
    video::Rasterize(object_cam, cam, kSurfaceObject, out.raster, options);
  }
  std::array<TriMesh, 2> hand_cam;
  for (int s = 0; s < 2; ++s) {
    if (!state.hands[s]) continue;
    hand_cam[s] = state.hands[s]->mesh.Transformed(cw);
    video::Rasterize(hand_cam[s], cam, s == 0 ? kSurfaceHandLeft : kSurfaceHandRight, out.raster,
                     options);
  }
  ShadeForeground(world, state, object_cam, hand_cam, shade, out);
  return out;
}

void AddSensorNoise(cv::Mat& bgr, double sigma, std::uint64_t seed) {
  if (sigma <= 0) return;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (int y = 0; y < bgr.rows; ++y) {
    std::uint8_t* row = bgr.ptr<std::uint8_t>(y);
    for (int i = 0; i < bgr.cols * bgr.channels(); ++i) {
      row[i] = static_cast<std::uint8_t>(std::clamp(std::lround(row[i] + noise(rng)), 0L, 255L));
    }
  }
}

cv::Mat SurfaceMask(const video::RasterTarget& raster, std::uint8_t id) {
  cv::Mat mask;
  cv::compare(raster.surface, id, mask, cv::CMP_EQ);
  return mask;
}

cv::Mat DepthToPoints(const cv::Mat& depth, const Camera& camera) {
  cv::Mat points(depth.rows, depth.cols, CV_32FC3);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int y = 0; y < depth.rows; ++y) {
    for (int x = 0; x < depth.cols; ++x) {
      const float z = depth.at<float>(y, x);
      if (!std::isfinite(z) || z <= 0) {
        points.at<cv::Vec3f>(y, x) = cv::Vec3f(nan, nan, nan);
        continue;
      }
      const Vec3 p = camera.Unproject(x, y, z);
      points.at<cv::Vec3f>(y, x) = cv::Vec3f(p.x(), p.y(), p.z());
    }
  }
  return points;
}

}  // namespace doasido::synth
