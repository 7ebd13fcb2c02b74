// Hand-object alignment exactly as seed §3.1 and its appendix define it.
// The hand (HaWoR) is taken as metric truth; the object pose (SAM 3D, in
// MoGe point-map units) keeps its rotation and gets one translation scale
// per frame:
//   c_hand^H  mean first hit on the hand mesh of one ray per hand-mask pixel
//   c_hand^M  mean point-map value over the same pixels
//   c_obj^M   mean point-map value over the object mask
//   k         = z_hand^H / z_hand^M
//   target    = c_hand^H + k (c_obj^M - c_hand^M)
//   c_mesh    centroid of the visible object surface inside the object mask,
//             rotated, translation excluded: the mean first hit (minus the
//             translation) of one ray per mask pixel onto the mesh posed at
//             the metric pose (R, s t), first with s = t^T target / t^T t,
//             then once more with s*
//   s*        = t^T (target - c_mesh) / t^T t   (1-D least squares)
// Both hands pool their pixels (each onto its own mesh). The seed averages
// the visible mesh vertices inside the mask for c_mesh; vertices weigh the
// surface by tessellation (a box has 8, a revolved cylinder none inside its
// sides), and an area-weighted sample still differs from the pixel-weighted
// c_obj^M by perspective: 1 % of the translation on exact synthetic data.
// Casting the mask's pixels makes c_mesh and c_obj^M average the same
// surface the same way, so noise-free data give the exact scale.
//
// Frames without evidence (no hand pixel striking a hand mesh, no valid
// depth, no object mask, no pose) are skipped with a recorded reason; gaps
// of at most max_gap_frames between aligned frames get linearly
// interpolated scales; frames beyond stay without a scale. With `smooth`,
// all scales are re-solved as one Ceres problem: the per-frame residuals
// c_mesh + s t - target under a Huber loss (outlier frames lose weight),
// plus smooth_weight times the second difference of the scaled object
// positions s_t t_t. The prior acts on positions, not on the raw scales,
// because MoGe's scale error is independent from frame to frame and so is
// the correct s_t; what is smooth is the metric trajectory.
#pragma once

#include <string>
#include <vector>

#include "core/config.h"
#include "core/geometry.h"
#include "core/mesh.h"
#include "recon/bundle/bundle.h"

namespace doasido::recon {

struct HandObjectAlignmentConfig {
  int min_hand_hits = 20;              // pixels striking a hand mesh
  int min_object_pixels = 20;          // object-mask pixels with valid depth
  int max_gap_frames = 15;             // longest run of skipped frames filled by interpolation
  bool smooth = false;
  double smooth_weight = 1.0;          // acceleration prior against the per-frame residuals
  double robust_scale = 0.01;          // m, Huber loss scale of the per-frame residuals
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(HandObjectAlignmentConfig, min_hand_hits,
                                                min_object_pixels, max_gap_frames, smooth,
                                                smooth_weight, robust_scale)
void CheckConfig(const HandObjectAlignmentConfig& c, const std::string& section);

// Why a frame has no alignment evidence (FrameAlignment::skipped).
inline constexpr const char* kSkipNoPose = "no_pose";
inline constexpr const char* kSkipNoDepth = "no_depth";
inline constexpr const char* kSkipNoHand = "no_hand_evidence";
inline constexpr const char* kSkipNoObjectMask = "no_object_mask";
inline constexpr const char* kSkipNoVisibleObject = "object_mesh_not_in_mask";

struct FrameAlignment {
  bool aligned = false;
  std::string skipped;  // one of kSkip*, empty when aligned
  int hand_hits = 0, object_pixels = 0;
  double k = 0;         // z_hand^H / z_hand^M
  double scale = 0;     // s*
  Vec3 c_hand_H = Vec3::Zero(), c_hand_M = Vec3::Zero(), c_obj_M = Vec3::Zero();
  Vec3 target = Vec3::Zero(), c_mesh = Vec3::Zero();
};

// How a frame got its scale.
inline constexpr const char* kFillAligned = "aligned";
inline constexpr const char* kFillInterpolated = "interpolated";
inline constexpr const char* kFillNone = "none";

struct HandObjectAlignment {
  std::vector<FrameAlignment> frames;  // (T) per-frame evidence
  std::vector<double> scale;           // (T) final scale, NaN where none
  std::vector<std::string> fill;       // (T) kFill*
  std::vector<Pose> poses;             // (T) object->camera, metric where scale is finite
  int aligned_frames = 0;
};

// s* = t^T (target - c_mesh) / t^T t; NaN when t is zero.
double TranslationScale(const Vec3& t, const Vec3& c_mesh, const Vec3& target);

// The evidence of frame t for the object pose `pose` (object->camera, point
// map units).
FrameAlignment MeasureFrame(const ClipBundle& bundle, int t, const TriMesh& object, const Pose& pose,
                            const HandObjectAlignmentConfig& config);

// Aligns every frame. `poses` (T) object->camera in point-map units,
// `pose_valid` (T). Requires bundle.object_mesh.
HandObjectAlignment AlignHandObject(const ClipBundle& bundle, const std::vector<Pose>& poses,
                                    const std::vector<bool>& pose_valid,
                                    const HandObjectAlignmentConfig& config);

// The Ceres re-solve described in the file comment, over the frames that
// have a scale (runs of consecutive frames share the prior). Returns the
// new scales (NaN kept where `alignment.scale` is NaN).
std::vector<double> SmoothScales(const HandObjectAlignment& alignment,
                                 const std::vector<Pose>& poses,
                                 const HandObjectAlignmentConfig& config);

}  // namespace doasido::recon
