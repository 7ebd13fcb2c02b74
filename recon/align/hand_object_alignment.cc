#include "recon/align/hand_object_alignment.h"

#include <cmath>
#include <limits>


#include "core/config_check.h"
#include "recon/ray_caster.h"
#include "recon/align/visible_centroid.h"

namespace doasido::recon {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool HasFrame(const std::vector<cv::Mat>& masks, int t) {
  return static_cast<size_t>(t) < masks.size() && !masks[t].empty();
}

// Pools the visible-hand sums of both hands (each mask onto its own mesh).
VisibleHand CastHands(const ClipBundle& b, int t, const cv::Mat& points) {
  VisibleHand sum;
  const std::pair<const std::optional<HandTrack>*, const std::vector<cv::Mat>*> hands[] = {
      {&b.hand_left, &b.mask_hand_left}, {&b.hand_right, &b.mask_hand_right}};
  for (const auto& [track, masks] : hands) {
    if (!*track || !HasFrame(*masks, t)) continue;
    const HandTrack& h = **track;
    if (static_cast<size_t>(t) >= h.verts.size() || h.verts[t].rows() == 0 || h.faces.rows() == 0)
      continue;
    if (static_cast<size_t>(t) < h.valid.size() && !h.valid[t]) continue;
    const RayCaster caster(h.verts[t], h.faces);
    sum += CastHandMask(caster, b.KAt(t), (*masks)[t], points);
  }
  return sum;
}

// c_mesh: the mean first hit, minus the translation, of one ray per
// object-mask pixel onto the object posed at `pose` (count = rays that hit).
// Pixel-weighted like c_obj^M, so both average the same visible surface.
Vec3 VisibleMeshCentroid(const TriMesh& object, const Pose& pose, const Mat3& K,
                         const cv::Mat& mask, int* count) {
  const RayCaster caster(object.Transformed(pose).vertices, object.faces);
  const Mat3 k_inv = K.inverse();
  Vec3 sum = Vec3::Zero();
  int n = 0;
  for (int v = 0; v < mask.rows; ++v) {
    const std::uint8_t* m = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < mask.cols; ++u) {
      if (!m[u]) continue;
      const Vec3 dir = (k_inv * Vec3(u, v, 1)).normalized();
      if (const auto hit = caster.FirstHit(Vec3::Zero(), dir)) {
        sum += *hit * dir - pose.t;
        ++n;
      }
    }
  }
  *count = n;
  return n ? Vec3(sum / n) : Vec3::Zero();
}

// Linear interpolation of NaN runs of at most `max_gap` between two finite scales.
void FillGaps(std::vector<double>& scale, std::vector<std::string>& fill, int max_gap) {
  const int T = static_cast<int>(scale.size());
  int last = -1;
  for (int t = 0; t < T; ++t) {
    if (!std::isfinite(scale[t])) continue;
    if (last >= 0 && t - last > 1 && t - last - 1 <= max_gap) {
      for (int g = last + 1; g < t; ++g) {
        const double a = double(g - last) / (t - last);
        scale[g] = (1 - a) * scale[last] + a * scale[t];
        fill[g] = kFillInterpolated;
      }
    }
    last = t;
  }
}

}  // namespace

void CheckConfig(const HandObjectAlignmentConfig& c, const std::string& section) {
  RequireInRange(section, "min_hand_hits", c.min_hand_hits, 1, 1e9);
  RequireInRange(section, "min_object_pixels", c.min_object_pixels, 1, 1e9);
  RequireInRange(section, "max_gap_frames", c.max_gap_frames, 0, 1e6);
  RequireInRange(section, "smooth_weight", c.smooth_weight, 0, 1e6);
  RequireInRange(section, "robust_scale", c.robust_scale, 1e-6, 10);
}

double TranslationScale(const Vec3& t, const Vec3& c_mesh, const Vec3& target) {
  const double tt = t.squaredNorm();
  return tt > 0 ? t.dot(target - c_mesh) / tt : kNaN;
}

FrameAlignment MeasureFrame(const ClipBundle& b, int t, const TriMesh& object, const Pose& pose,
                            const HandObjectAlignmentConfig& config) {
  FrameAlignment f;
  if (static_cast<size_t>(t) >= b.depth.size() && static_cast<size_t>(t) >= b.points.size()) {
    f.skipped = kSkipNoDepth;
    return f;
  }
  if (!HasFrame(b.mask_object, t) || cv::countNonZero(b.mask_object[t]) == 0) {
    f.skipped = kSkipNoObjectMask;
    return f;
  }
  const cv::Mat points = PointMapAt(b, t);
  f.c_obj_M = MaskCentroid(b.mask_object[t], points, &f.object_pixels);
  if (f.object_pixels < config.min_object_pixels) {
    f.skipped = kSkipNoDepth;
    return f;
  }
  const VisibleHand hand = CastHands(b, t, points);
  f.hand_hits = hand.hits;
  if (hand.hits < config.min_hand_hits) {
    f.skipped = kSkipNoHand;
    return f;
  }
  f.c_hand_H = hand.MeshCentroid();
  f.c_hand_M = hand.MapCentroid();
  f.k = f.c_hand_H.z() / f.c_hand_M.z();
  f.target = f.c_hand_H + f.k * (f.c_obj_M - f.c_hand_M);
  // Which points are visible and inside the mask is decided at the metric
  // pose (the mesh is metric, the model translation is not): first at the
  // scale that puts the origin nearest the target, then at s* once more.
  f.scale = TranslationScale(pose.t, Vec3::Zero(), f.target);
  for (int pass = 0; pass < 2 && std::isfinite(f.scale) && f.scale > 0; ++pass) {
    int visible = 0;
    f.c_mesh = VisibleMeshCentroid(object, {pose.q, f.scale * pose.t}, b.KAt(t),
                                   b.mask_object[t], &visible);
    if (visible == 0) {
      f.skipped = kSkipNoVisibleObject;
      return f;
    }
    f.scale = TranslationScale(pose.t, f.c_mesh, f.target);
  }
  f.aligned = std::isfinite(f.scale) && f.scale > 0;
  if (!f.aligned) f.skipped = kSkipNoVisibleObject;
  return f;
}

HandObjectAlignment AlignHandObject(const ClipBundle& b, const std::vector<Pose>& poses,
                                    const std::vector<bool>& pose_valid,
                                    const HandObjectAlignmentConfig& config) {
  const TriMesh& object = *b.object_mesh;
  const int T = b.frames;
  HandObjectAlignment a;
  a.scale.assign(T, kNaN);
  a.fill.assign(T, kFillNone);
  for (int t = 0; t < T; ++t) {
    const bool has_pose = static_cast<size_t>(t) < poses.size() && pose_valid[t];
    FrameAlignment f;
    if (has_pose) {
      f = MeasureFrame(b, t, object, poses[t], config);
    } else {
      f.skipped = kSkipNoPose;
    }
    if (f.aligned) {
      a.scale[t] = f.scale;
      a.fill[t] = kFillAligned;
      ++a.aligned_frames;
    }
    a.frames.push_back(f);
  }
  FillGaps(a.scale, a.fill, config.max_gap_frames);
  for (int t = 0; t < T; ++t) {
    if (a.fill[t] == kFillInterpolated && !(static_cast<size_t>(t) < poses.size() && pose_valid[t])) {
      a.scale[t] = kNaN;  // no pose to scale
      a.fill[t] = kFillNone;
    }
  }
  if (config.smooth && a.aligned_frames > 0) a.scale = SmoothScales(a, poses, config);
  a.poses.assign(T, Pose::Identity());
  for (int t = 0; t < T; ++t) {
    if (std::isfinite(a.scale[t])) a.poses[t] = {poses[t].q, a.scale[t] * poses[t].t};
  }
  return a;
}

}  // namespace doasido::recon
