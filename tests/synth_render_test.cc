// Rendered frames agree with the ground truth written beside them:
// silhouettes of the true meshes projected through K match the masks, and
// depth ray-cast from the true meshes equals the rendered depth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "synth/generator.h"
#include "synth/render.h"

namespace doasido::synth {
namespace {

// Silhouette of a camera-frame mesh: pixels whose centre lies inside some
// projected triangle (point-in-triangle by signs, no depth test; an
// independent path from the z-buffer rasteriser).
cv::Mat Silhouette(const Eigen::MatrixX3d& verts,
                   const Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>& faces,
                   const Camera& cam) {
  cv::Mat m = cv::Mat::zeros(cam.height, cam.width, CV_8U);
  for (int f = 0; f < faces.rows(); ++f) {
    Vec2 q[3];
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = verts.row(faces(f, k)).transpose();
      if (p.z() <= 0.01) ok = false;
      q[k] = cam.Project(p);
    }
    if (!ok) continue;
    const int x0 = std::max(0, (int)std::floor(std::min({q[0].x(), q[1].x(), q[2].x()})));
    const int x1 =
        std::min(cam.width - 1, (int)std::ceil(std::max({q[0].x(), q[1].x(), q[2].x()})));
    const int y0 = std::max(0, (int)std::floor(std::min({q[0].y(), q[1].y(), q[2].y()})));
    const int y1 =
        std::min(cam.height - 1, (int)std::ceil(std::max({q[0].y(), q[1].y(), q[2].y()})));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const Vec2 p(x, y);
        double s[3];
        for (int k = 0; k < 3; ++k) {
          const Vec2 a = q[k], b = q[(k + 1) % 3];
          s[k] = (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
        }
        if ((s[0] >= 0 && s[1] >= 0 && s[2] >= 0) || (s[0] <= 0 && s[1] <= 0 && s[2] <= 0)) {
          m.at<std::uint8_t>(y, x) = 255;
        }
      }
    }
  }
  return m;
}

double IoU(const cv::Mat& a, const cv::Mat& b) {
  const double inter = cv::countNonZero(a & b), uni = cv::countNonZero(a | b);
  return uni > 0 ? inter / uni : 1.0;
}

// Nearest ray hit (Moller-Trumbore), camera-frame z; inf when missed.
double RayDepth(const Eigen::MatrixX3d& v,
                const Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>& f, const Vec3& dir) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < f.rows(); ++i) {
    const Vec3 a = v.row(f(i, 0)), b = v.row(f(i, 1)), c = v.row(f(i, 2));
    const Vec3 e1 = b - a, e2 = c - a, p = dir.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-15) continue;
    const double u = -a.dot(p) / det;
    if (u < 0 || u > 1) continue;
    const Vec3 q = (-a).cross(e1);
    const double w = dir.dot(q) / det;
    if (w < 0 || u + w > 1) continue;
    const double s = e2.dot(q) / det;
    if (s > 0) best = std::min(best, s * dir.z());
  }
  return best;
}

struct Part {
  Eigen::MatrixX3d verts;
  Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> faces;
  const cv::Mat* mask;
};

class RenderTruth : public ::testing::TestWithParam<DefectKind> {};

TEST_P(RenderTruth, SilhouettesAndDepthMatchTheGroundTruthMeshes) {
  SynthConfig cfg;
  cfg.width = 320;
  cfg.height = 240;
  cfg.frames = 30;
  cfg.seed = 11;
  cfg.two_hand_fraction = 1.0;
  const RenderedClip clip = RenderClip(cfg, 2, GetParam());
  const recon::ClipBundle& b = clip.bundle;
  ASSERT_EQ(static_cast<int>(clip.bgr.size()), cfg.frames);
  int checked_frames = 0;
  double min_iou = 1.0, min_depth_agreement = 1.0;
  for (int t = 0; t < cfg.frames; t += 4) {
    const Camera cam = Camera::FromK(b.K.size() == 1 ? b.K[0] : b.K[t], b.width, b.height);
    std::vector<Part> parts;
    parts.push_back({b.object_mesh->Transformed(b.object_poses[t]).vertices, b.object_mesh->faces,
                     &b.mask_object[t]});
    if (b.hand_left && b.hand_left->valid[t]) {
      parts.push_back({b.hand_left->verts[t], b.hand_left->faces, &b.mask_hand_left[t]});
    }
    if (b.hand_right && b.hand_right->valid[t]) {
      parts.push_back({b.hand_right->verts[t], b.hand_right->faces, &b.mask_hand_right[t]});
    }
    cv::Mat all_sil = cv::Mat::zeros(cam.height, cam.width, CV_8U), all_mask = all_sil.clone();
    for (const Part& p : parts) {
      const cv::Mat sil = Silhouette(p.verts, p.faces, cam);
      all_sil |= sil;
      all_mask |= *p.mask;
      // Visible pixels of a part lie inside its own silhouette.
      const int visible = cv::countNonZero(*p.mask);
      if (visible > 50) {
        EXPECT_GE(cv::countNonZero(*p.mask & sil), 0.97 * visible) << "frame " << t;
      }
    }
    // Hands and object occlude only each other, so the union is exact.
    if (cv::countNonZero(all_mask) > 200) {
      min_iou = std::min(min_iou, IoU(all_sil, all_mask));
      EXPECT_GE(IoU(all_sil, all_mask), 0.95)
          << "frame " << t << " sil-only " << cv::countNonZero(all_sil & ~all_mask) << " mask-only "
          << cv::countNonZero(all_mask & ~all_sil) << " mask " << cv::countNonZero(all_mask);
      ++checked_frames;
    }
    // Depth: cast rays through a grid of masked pixels.
    int rays = 0, agree = 0;
    for (int y = 0; y < cam.height; y += 5) {
      for (int x = 0; x < cam.width; x += 5) {
        if (!all_mask.at<std::uint8_t>(y, x)) continue;
        const Vec3 dir((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1.0);
        double z = std::numeric_limits<double>::infinity();
        for (const Part& p : parts) z = std::min(z, RayDepth(p.verts, p.faces, dir));
        ++rays;
        agree += std::abs(z - b.depth[t].at<float>(y, x)) < 1e-5 * z + 1e-6;
      }
    }
    if (rays > 0) {
      EXPECT_GE(agree, 0.98 * rays) << "frame " << t;
      min_depth_agreement = std::min(min_depth_agreement, static_cast<double>(agree) / rays);
    }
  }
  EXPECT_GE(checked_frames, 4);
  std::printf("%s: min silhouette IoU %.4f, min fraction of rays with equal depth %.4f\n",
              DefectName(GetParam()), min_iou, min_depth_agreement);
}

INSTANTIATE_TEST_SUITE_P(Kinds, RenderTruth,
                         ::testing::Values(DefectKind::kClean, DefectKind::kZoom, DefectKind::kCut,
                                           DefectKind::kObjectOut),
                         [](const auto& p) { return std::string(DefectName(p.param)); });

TEST(Render, SkinIsSkinColouredAndObjectIsNot) {
  SynthConfig cfg;
  cfg.width = 320;
  cfg.height = 240;
  cfg.frames = 24;
  cfg.sensor_noise = 0;
  const RenderedClip clip = RenderClip(cfg, 0, DefectKind::kClean);
  // A classical YCrCb skin box (Cr 135-180, Cb 85-135) holds most hand pixels.
  int hand = 0, skin = 0;
  for (int t = 0; t < cfg.frames; t += 6) {
    cv::Mat ycc;
    cv::cvtColor(clip.bgr[t], ycc, cv::COLOR_BGR2YCrCb);
    const cv::Mat& mask =
        clip.bundle.hand_right ? clip.bundle.mask_hand_right[t] : clip.bundle.mask_hand_left[t];
    for (int y = 0; y < ycc.rows; ++y) {
      for (int x = 0; x < ycc.cols; ++x) {
        if (!mask.at<std::uint8_t>(y, x)) continue;
        const cv::Vec3b p = ycc.at<cv::Vec3b>(y, x);
        ++hand;
        skin += p[1] >= 135 && p[1] <= 180 && p[2] >= 85 && p[2] <= 135;
      }
    }
  }
  ASSERT_GT(hand, 100);
  EXPECT_GT(static_cast<double>(skin) / hand, 0.7);
}

}  // namespace
}  // namespace doasido::synth
