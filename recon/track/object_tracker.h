// Frame-by-frame object tracking with a flow-matching model (seed §3.1):
// the shape is fixed at the anchor frame (frame 0 here: the shape block of
// the candidate chosen among its unguided samples); at every later frame k, N candidates are
// drawn with guided Euler sampling (recon/track/guided_flow.h) toward the anchor
// shape and the pose chosen at k - 1, with that frame's alpha_p
// (recon/track/adaptive_guidance.h, or a fixed value); one candidate is chosen
// (recon/track/pose_selection.h) and becomes the next frame's reference.
#pragma once

#include <functional>
#include <vector>

#include "recon/track/guided_flow.h"
#include "recon/track/pose_selection.h"
#include "recon/track/velocity_field.h"

namespace doasido::recon {

struct TrackedFrame {
  Pose pose;                   // the chosen candidate
  PoseChoice choice;
  double pose_guidance = 0;    // alpha_p used
  std::vector<Pose> candidates;
  double sampling_seconds = 0;   // drawing the candidates
  double selection_seconds = 0;  // choosing one
};

struct TrackInputs {
  std::vector<double> pose_guidance;  // alpha_p per frame ([0] unused)
  // Silhouette IoU of a pose at frame k against that frame's mask (for
  // clustering selection); may be empty for the other methods. Called from
  // several threads at once (GuidedFlowConfig::threads).
  std::function<double(int, const Pose&)> silhouette_iou;
};

// Tracks frames [0, frames) of `model`. Deterministic for config seeds.
std::vector<TrackedFrame> TrackObject(VelocityField& model, int frames,
                                      const TrackInputs& inputs, const GuidedFlowConfig& flow,
                                      const PoseSelectionConfig& selection);

}  // namespace doasido::recon
