// The seed's tracking ablation (appendix Table 4) in kind, on synthetic
// sequences (synth/tracking_scene.h): {fixed, adaptive} pose guidance x
// {random, likelihood, clustering} selection, scored by F-5, F-10 and
// Chamfer distance of the object surface at the chosen pose against the
// true pose (camera frame, recon/recon_metrics.h), averaged over all frames.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "recon/track/guided_flow.h"
#include "recon/track/pose_selection.h"
#include "synth/tracking_scene.h"

namespace doasido::synth {

struct TrackingAblationOptions {
  int sequences = 50;
  std::uint64_t seed = 1;
  double fixed_pose_guidance = 0.5;  // the seed does not say its fixed value
  int metric_points = 2000;          // surface samples per pose
  TrackingSceneOptions scene;
  recon::GuidedFlowConfig flow;
  recon::PoseSelectionConfig selection;
};

struct TrackingAblationCell {
  std::string guidance;    // "fixed" / "adaptive"
  std::string selection;   // recon::kSelect*
  double f_5mm = 0, f_10mm = 0, cd_sq_cm2 = 0, cd_l1_cm = 0;
  double flip_share = 0;      // frames whose pose is off by more than 90 degrees
  double rotation_error_deg = 0;  // mean
  double sampling_seconds = 0;   // guided sampling, all frames
  double selection_seconds = 0;  // choosing among the candidates, all frames
  int frames = 0;
};

std::vector<TrackingAblationCell> RunTrackingAblation(const TrackingAblationOptions& options);

}  // namespace doasido::synth
