#include "recon/track/silhouette.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace doasido::recon {

SilhouetteRenderer::SilhouetteRenderer(const TriMesh& mesh)
    : mesh_(mesh), caster_(mesh.vertices, mesh.faces) {}

cv::Rect SilhouetteRenderer::Footprint(const Pose& pose, const Camera& camera) const {
  const cv::Rect image(0, 0, camera.width, camera.height);
  double lo_u = INFINITY, lo_v = INFINITY, hi_u = -INFINITY, hi_v = -INFINITY;
  for (int i = 0; i < mesh_.num_vertices(); ++i) {
    const Vec3 p = pose * Vec3(mesh_.vertices.row(i).transpose());
    if (p.z() <= 1e-9) return image;
    const Vec2 uv = camera.Project(p);
    lo_u = std::min(lo_u, uv.x());
    lo_v = std::min(lo_v, uv.y());
    hi_u = std::max(hi_u, uv.x());
    hi_v = std::max(hi_v, uv.y());
  }
  if (!(lo_u <= hi_u)) return {};
  const cv::Rect box(cv::Point(static_cast<int>(std::floor(std::max(-1.0, lo_u))),
                               static_cast<int>(std::floor(std::max(-1.0, lo_v)))),
                     cv::Point(static_cast<int>(std::ceil(std::min(1e6, hi_u))) + 2,
                               static_cast<int>(std::ceil(std::min(1e6, hi_v))) + 2));
  return box & image;
}

bool SilhouetteRenderer::Hits(const Pose& inverse, const Camera& camera, int u, int v) const {
  const Vec3 direction = inverse.q * camera.Unproject(u, v, 1.0);
  return caster_.FirstHit(inverse.t, direction).has_value();
}

cv::Mat SilhouetteRenderer::Render(const Pose& pose, const Camera& camera, int stride) const {
  if (stride < 1) throw Error("bad_config", "silhouette stride must be >= 1");
  const Pose inverse = pose.Inverse();
  cv::Mat out(camera.height, camera.width, CV_8U, cv::Scalar(0));
  for (int v = 0; v < camera.height; v += stride) {
    for (int u = 0; u < camera.width; u += stride) {
      if (!Hits(inverse, camera, u, v)) continue;
      out(cv::Rect(u, v, std::min(stride, camera.width - u), std::min(stride, camera.height - v)))
          .setTo(255);
    }
  }
  return out;
}

double SilhouetteRenderer::IoU(const Pose& pose, const Camera& camera, const cv::Mat& mask,
                               int stride, const cv::Mat& occluders) const {
  for (const cv::Mat* m : {&mask, &occluders}) {
    if (m == &occluders && m->empty()) continue;
    if (m->rows != camera.height || m->cols != camera.width || m->type() != CV_8U) {
      throw Error("bad_mask", "a mask is not an 8-bit image of the camera's size");
    }
  }
  const Pose inverse = pose.Inverse();
  const cv::Rect area = Footprint(pose, camera) | cv::boundingRect(mask);
  long both = 0, either = 0;
  // Sampled pixels stay on the image's stride grid whatever the area.
  const int v0 = (area.y + stride - 1) / stride * stride, u0 = (area.x + stride - 1) / stride * stride;
  for (int v = v0; v < area.y + area.height; v += stride) {
    for (int u = u0; u < area.x + area.width; u += stride) {
      if (!occluders.empty() && occluders.at<std::uint8_t>(v, u) != 0) continue;
      const bool in_mask = mask.at<std::uint8_t>(v, u) != 0;
      const bool hit = Hits(inverse, camera, u, v);
      both += in_mask && hit;
      either += in_mask || hit;
    }
  }
  return either == 0 ? 0.0 : static_cast<double>(both) / either;
}

}  // namespace doasido::recon
