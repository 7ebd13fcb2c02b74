#include "video/mesh_rasterizer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace doasido::video {
namespace {

struct ScreenVertex {
  double u, v, inv_z;
};

// Rasterises one screen-space triangle whose vertices are all in front of
// the camera.
std::int64_t DrawTriangle(const ScreenVertex& a, const ScreenVertex& b, const ScreenVertex& c,
                          int face, std::uint8_t id, RasterTarget& t) {
  const double area = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
  if (area == 0 || !std::isfinite(area)) return 0;
  const int w = t.depth.cols, h = t.depth.rows;
  const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({a.u, b.u, c.u}))));
  const int x1 = std::min(w - 1, static_cast<int>(std::floor(std::max({a.u, b.u, c.u}))));
  const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({a.v, b.v, c.v}))));
  const int y1 = std::min(h - 1, static_cast<int>(std::floor(std::max({a.v, b.v, c.v}))));
  if (x0 > x1 || y0 > y1) return 0;
  const double inv_area = 1.0 / area;
  // Edge function e_i(x, y) = A_i x + B_i y + C_i, weight of the opposite vertex.
  auto edge = [&](const ScreenVertex& p, const ScreenVertex& q, double& A, double& B, double& C) {
    A = (p.v - q.v) * inv_area;
    B = (q.u - p.u) * inv_area;
    C = (p.u * q.v - p.v * q.u) * inv_area;
  };
  double A0, B0, C0, A1, B1, C1, A2, B2, C2;
  edge(b, c, A0, B0, C0);  // weight of a
  edge(c, a, A1, B1, C1);  // weight of b
  edge(a, b, A2, B2, C2);  // weight of c
  std::int64_t written = 0;
  constexpr double kEps = -1e-12;
  for (int y = y0; y <= y1; ++y) {
    float* drow = t.depth.ptr<float>(y);
    std::uint8_t* srow = t.surface.ptr<std::uint8_t>(y);
    int* frow = t.face.ptr<int>(y);
    double w0 = A0 * x0 + B0 * y + C0, w1 = A1 * x0 + B1 * y + C1, w2 = A2 * x0 + B2 * y + C2;
    for (int x = x0; x <= x1; ++x, w0 += A0, w1 += A1, w2 += A2) {
      if (w0 < kEps || w1 < kEps || w2 < kEps) continue;
      const double inv_z = w0 * a.inv_z + w1 * b.inv_z + w2 * c.inv_z;
      if (inv_z <= 0) continue;
      const float z = static_cast<float>(1.0 / inv_z);
      if (z < drow[x]) {
        drow[x] = z;
        srow[x] = id;
        frow[x] = face;
        ++written;
      }
    }
  }
  return written;
}

ScreenVertex ToScreen(const Vec3& p, const Camera& cam) {
  return {cam.fx * p.x() / p.z() + cam.cx, cam.fy * p.y() / p.z() + cam.cy, 1.0 / p.z()};
}

}  // namespace

void RasterTarget::Reset(int width, int height) {
  depth.create(height, width, CV_32F);
  surface.create(height, width, CV_8U);
  face.create(height, width, CV_32S);
  depth.setTo(std::numeric_limits<float>::infinity());
  surface.setTo(0);
  face.setTo(-1);
}

std::int64_t Rasterize(const TriMesh& mesh, const Camera& cam, std::uint8_t id,
                       RasterTarget& target, const RasterOptions& options) {
  std::int64_t written = 0;
  const double near = options.near;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    std::array<Vec3, 3> p;
    int behind = 0;
    for (int k = 0; k < 3; ++k) {
      p[k] = mesh.vertices.row(mesh.faces(f, k)).transpose();
      behind += p[k].z() < near;
    }
    if (behind == 3) continue;
    if (options.cull_back && p[0].dot((p[1] - p[0]).cross(p[2] - p[0])) >= 0) continue;
    if (behind == 0) {
      written += DrawTriangle(ToScreen(p[0], cam), ToScreen(p[1], cam), ToScreen(p[2], cam), f, id,
                              target);
      continue;
    }
    // Sutherland-Hodgman against z = near; the result has 3 or 4 vertices.
    std::array<Vec3, 4> poly;
    int n = 0;
    for (int k = 0; k < 3; ++k) {
      const Vec3& cur = p[k];
      const Vec3& nxt = p[(k + 1) % 3];
      const bool cur_in = cur.z() >= near, nxt_in = nxt.z() >= near;
      if (cur_in) poly[n++] = cur;
      if (cur_in != nxt_in) {
        const double s = (near - cur.z()) / (nxt.z() - cur.z());
        poly[n++] = cur + s * (nxt - cur);
      }
    }
    const ScreenVertex s0 = ToScreen(poly[0], cam);
    for (int k = 1; k + 1 < n; ++k) {
      written +=
          DrawTriangle(s0, ToScreen(poly[k], cam), ToScreen(poly[k + 1], cam), f, id, target);
    }
  }
  return written;
}

std::int64_t RasterizeBruteForce(const TriMesh& mesh, const Camera& cam, std::uint8_t id,
                                 RasterTarget& t) {
  std::vector<std::array<ScreenVertex, 3>> tris(mesh.num_faces());
  for (int f = 0; f < mesh.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      tris[f][k] = ToScreen(mesh.vertices.row(mesh.faces(f, k)).transpose(), cam);
    }
  }
  std::int64_t written = 0;
  for (int y = 0; y < t.depth.rows; ++y) {
    for (int x = 0; x < t.depth.cols; ++x) {
      for (int f = 0; f < mesh.num_faces(); ++f) {
        const auto& [a, b, c] = tris[f];
        const double area = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
        if (area == 0) continue;
        const double w0 = ((b.u - x) * (c.v - y) - (b.v - y) * (c.u - x)) / area;
        const double w1 = ((c.u - x) * (a.v - y) - (c.v - y) * (a.u - x)) / area;
        const double w2 = 1.0 - w0 - w1;
        if (w0 < -1e-12 || w1 < -1e-12 || w2 < -1e-12) continue;
        const double inv_z = w0 * a.inv_z + w1 * b.inv_z + w2 * c.inv_z;
        const float z = static_cast<float>(1.0 / inv_z);
        if (z < t.depth.at<float>(y, x)) {
          t.depth.at<float>(y, x) = z;
          t.surface.at<std::uint8_t>(y, x) = id;
          t.face.at<int>(y, x) = f;
          ++written;
        }
      }
    }
  }
  return written;
}

}  // namespace doasido::video
