// The `track` queue stage, between `bundle` and `recon`: tracks the object
// frame by frame with guided flow sampling (recon/track/object_tracker.h) and
// writes the poses the recon stage uses instead of the bundle's.
//
// The object model, first found of:
//   server       track.server, a velocity-server command
//                (recon/track/velocity_server.h; {bundle} and {clip} are replaced
//                by the bundle folder and the clip's name), e.g.
//                "/usr/bin/python3 tools/velocity_server.py {bundle}/object/flow_modes.npz"
//   candidates   the bundle's object/candidates.npz, pose samples a model
//                drew per frame, taken as the model: a Gaussian mixture with
//                one mode per sample (kde_sigma wide, the pose block only).
// A bundle with neither is passed on untouched, saying so (measurement
// track_source "none"); recon then uses the bundle's own poses. A bundle
// without any object part (a hand-only bundle, e.g. the hands stage's) is
// passed at once, even with a server configured (track_source "no_object").
// Pose guidance: adaptive (recon/track/adaptive_guidance.h) from the bundle's
// point tracks (guidance_source "tracks"), else from OpenCV's Lucas-Kanade
// on the clip's video ("lucas_kanade", recon/track/lucas_kanade_follower.h),
// else the fixed `pose_guidance` ("fixed"). Selection per `selection.method`; clustering
// needs the object mesh and masks (the hands' masks count as occluders).
//
// Output in artifact_dir (<artifacts>/<clip>/track/):
//   object_poses.npz  poses (T,7) f8 t xyz + q wxyz object->camera (the
//                     file recon reads), candidates (T,N,7) f8, chosen (T)
//                     i8, score (T) f8, alpha_p (T) f8
//   track.log         the server's stderr (server model only)
#pragma once

#include <string>

#include "core/config.h"
#include "recon/track/adaptive_guidance.h"
#include "recon/track/guided_flow.h"
#include "recon/track/pose_selection.h"
#include "stages/stage.h"

namespace doasido::stages {

inline constexpr const char* kTrackStageName = "track";
inline constexpr const char* kTrackPosesFile = "object_poses.npz";

// Measurement keys and values.
inline constexpr const char* kMeasureTrackSource = "track_source";  // server / candidates / none / no_object
inline constexpr const char* kTrackSourceNoObject = "no_object";
inline constexpr const char* kMeasureGuidanceSource = "guidance_source";  // tracks / lucas_kanade / fixed
inline constexpr const char* kMeasureTrackedFrames = "tracked_frames";
inline constexpr const char* kMeasureMeanPoseGuidance = "mean_pose_guidance";
inline constexpr const char* kMeasureOutlierFrames = "outlier_only_frames";
inline constexpr const char* kMeasureSamplingSeconds = "sampling_seconds";
inline constexpr const char* kMeasureSelectionSeconds = "selection_seconds";

struct TrackStageConfig {
  std::string server;              // velocity-server command; "" = none
  double kde_sigma = 0.01;         // mode width of the candidates model
  double pose_guidance = 0.5;      // alpha_p without point tracks
  double track_radius_px = 3.0;    // a drawn pixel follows the nearest track this close
  recon::GuidedFlowConfig flow;
  recon::AdaptiveGuidanceConfig guidance;
  recon::PoseSelectionConfig selection;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(TrackStageConfig, server, kde_sigma,
                                                pose_guidance, track_radius_px, flow, guidance,
                                                selection)
void CheckConfig(const TrackStageConfig& c, const std::string& section);

class TrackStage : public Stage {
 public:
  explicit TrackStage(TrackStageConfig config = {});
  std::string Name() const override { return kTrackStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;

 private:
  TrackStageConfig config_;
};

}  // namespace doasido::stages
