// The reconstruction of one clip bundle, queue-independent (seed §3.1):
// hand-object alignment (hand_object_alignment.h) rescales each frame's
// object translation to the hand's metric scale; gravity (gravity.h)
// rotates camera coordinates so up is +z; the floor z = 0 is put under the
// object's resting pose. A hand-only bundle is reconstructed without
// object. The `recon` queue stage (stages/recon_stage.h) runs it on a
// clip's bundle and records the measurements named below.
#pragma once

#include <vector>

#include "core/config.h"
#include "core/geometry.h"
#include "recon/align/gravity.h"
#include "recon/align/hand_object_alignment.h"
#include "recon/bundle/bundle.h"
#include "recon/reconstruction.h"

namespace doasido::recon {

// Measurement keys.
inline constexpr const char* kMeasureFrames = "frames";
inline constexpr const char* kMeasurePosedFrames = "posed_frames";
inline constexpr const char* kMeasureAlignedFrames = "aligned_frames";
inline constexpr const char* kMeasureEvidenceShare = "evidence_share";  // aligned / posed
inline constexpr const char* kMeasureScaleMedian = "scale_median";
inline constexpr const char* kMeasureScaleSpread = "scale_spread";  // 1.4826 MAD of log s
inline constexpr const char* kMeasureHandObjectDistance = "hand_object_distance_m";  // per frame
inline constexpr const char* kMeasureHandObjectDistanceMedian = "hand_object_distance_median_m";
inline constexpr const char* kMeasurePoseJitter = "pose_jitter_m";  // median |acceleration| per frame
inline constexpr const char* kMeasureGravitySource = "gravity_source";
inline constexpr const char* kMeasureGravityInlierShare = "gravity_inlier_share";
inline constexpr const char* kMeasurePoseSource = "object_pose_source";  // "track" or "bundle"
// Hand-only reconstructions (no object part in the bundle).
inline constexpr const char* kMeasureObject = "object";              // kObjectNone when hand-only
inline constexpr const char* kObjectNone = "none";
inline constexpr const char* kMeasureGravityAssumed = "gravity_assumed";  // camera-up taken as up
inline constexpr const char* kMeasureIntrinsicsAssumed = "intrinsics_assumed";  // the hands stage's
inline constexpr const char* kMeasureRightFrames = "right_frames";    // frames the hand is seen
inline constexpr const char* kMeasureLeftFrames = "left_frames";
inline constexpr const char* kMeasureWristJumpMax = "wrist_jump_max_m";  // largest frame-to-frame step
inline constexpr const char* kMeasureBundleSource = "bundle_source";  // bundle_location.h kBundleFrom*
// A bundle whose producers name this key (the objects stage's: "hand_contact"
// or "category_prior", where the object's scale came from) has object poses
// that are already metric in the camera frame, not in a point map's units:
// Reconstruct takes them as they are (every posed frame "aligned" with
// scale 1, fill kFillMetric) instead of the seed's depth-based alignment,
// which needs depth and hand meshes such a bundle does not have.
inline constexpr const char* kObjectScaleProducer = "object_scale";
inline constexpr const char* kFillMetric = "metric";
bool ObjectPosesAreMetric(const ClipBundle& bundle);

// How far below the hands' lowest joint a hand-only clip's floor lies, m
// (recon and retarget_kinematic's bundle fallback agree on it).
inline constexpr double kHandOnlyFloorMargin = 0.05;


struct ReconStageConfig {
  HandObjectAlignmentConfig alignment;
  GravityConfig gravity;
  double min_aligned_fraction = 0.3;
  int min_aligned_frames = 5;
  double max_scale_spread = 0.25;
  double rest_speed = 0.002;  // m per frame
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ReconStageConfig, alignment, gravity,
                                                min_aligned_fraction, min_aligned_frames,
                                                max_scale_spread, rest_speed)

struct ReconOutput {
  Reconstruction reconstruction;  // object_mesh left empty (the caller writes the mesh)
  HandObjectAlignment alignment;
  GravityEstimate gravity;
  Mat3 camera_to_world = Mat3::Identity();  // rotation; then z -= floor offset
  double floor_offset = 0;
  Json measurements = Json::object();
};

// Aligns and gravity-aligns one bundle. `poses` (T) object->camera in point
// map units with `pose_valid`. Requires bundle.object_mesh.
ReconOutput Reconstruct(const ClipBundle& bundle, const std::vector<Pose>& poses,
                        const std::vector<bool>& pose_valid, const ReconStageConfig& config);

// A bundle with a hand and no object part at all (mesh, poses, candidates,
// masks): the hands stage's bundle, or a model command's without an object.
bool IsHandOnly(const ClipBundle& bundle);

// The hands alone: gravity from the bundle (gravity.npz, else the support
// plane of a point map), else camera-up recorded as assumed; the floor
// z = 0 kHandOnlyFloorMargin below the lowest joint of either hand; no
// object (object_valid all false, no mesh). Measurements kMeasureObject,
// kMeasureGravity*, kMeasureRight/LeftFrames, kMeasureWristJumpMax.
ReconOutput ReconstructHandOnly(const ClipBundle& bundle, const ReconStageConfig& config);

}  // namespace doasido::recon
