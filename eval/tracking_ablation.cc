#include "eval/tracking_ablation.h"

#include "recon/track/adaptive_guidance.h"
#include "recon/track/object_tracker.h"
#include "recon/recon_metrics.h"
#include "recon/track/silhouette.h"

namespace doasido::synth {
namespace {

recon::Points3 Placed(const recon::Points3& local, const Pose& pose) {
  recon::Points3 out(local.rows(), 3);
  for (Eigen::Index i = 0; i < local.rows(); ++i) {
    out.row(i) = (pose * Vec3(local.row(i).transpose())).transpose();
  }
  return out;
}

void Score(const TrackingScene& scene, const recon::Points3& surface,
           const std::vector<recon::TrackedFrame>& track, TrackingAblationCell* cell) {
  for (size_t k = 0; k < track.size(); ++k) {
    const recon::ReconMetrics m =
        recon::ComparePoints(Placed(surface, track[k].pose), Placed(surface, scene.truth[k]));
    cell->f_5mm += m.f_5mm;
    cell->f_10mm += m.f_10mm;
    cell->cd_sq_cm2 += m.cd_sq_cm2;
    cell->cd_l1_cm += m.cd_l1_cm;
    const double angle = RotationAngle(track[k].pose.q, scene.truth[k].q) * 180 / 3.14159265358979;
    cell->flip_share += angle > 90;
    cell->rotation_error_deg += angle;
    cell->sampling_seconds += track[k].sampling_seconds;
    cell->selection_seconds += track[k].selection_seconds;
    ++cell->frames;
  }
}

}  // namespace

std::vector<TrackingAblationCell> RunTrackingAblation(const TrackingAblationOptions& o) {
  std::vector<TrackingAblationCell> cells;
  for (const char* guidance : {"fixed", "adaptive"}) {
    for (const char* method : {recon::kSelectRandom, recon::kSelectLikelihood,
                               recon::kSelectClustering}) {
      cells.push_back({.guidance = guidance, .selection = method});
    }
  }
  for (int s = 0; s < o.sequences; ++s) {
    const TrackingScene scene = MakeTrackingScene(o.seed + s, o.scene);
    const recon::Points3 surface = recon::SampleSurface(scene.mesh, o.metric_points, o.seed + s);
    const recon::SilhouetteRenderer renderer(scene.mesh);
    recon::AdaptiveGuidanceConfig adaptive_config;
    adaptive_config.seed = o.seed + s;
    const std::vector<double> adaptive =
        recon::EstimatePoseGuidance(scene.masks, scene.follow, adaptive_config).alpha_p;
    const std::vector<double> fixed(scene.truth.size(), o.fixed_pose_guidance);
    recon::TrackInputs inputs;
    inputs.silhouette_iou = [&](int k, const Pose& pose) {
      return renderer.IoU(pose, scene.camera, scene.masks[k], o.selection.silhouette_stride,
                          scene.hand_masks[k]);
    };
    for (TrackingAblationCell& cell : cells) {
      inputs.pose_guidance = cell.guidance == "fixed" ? fixed : adaptive;
      recon::PoseSelectionConfig selection = o.selection;
      selection.method = cell.selection;
      selection.seed = o.seed + s;
      recon::GuidedFlowConfig flow = o.flow;
      flow.seed = o.flow.seed + s;
      Score(scene, surface,
            recon::TrackObject(*scene.model, static_cast<int>(scene.truth.size()), inputs, flow,
                               selection),
            &cell);
    }
  }
  for (TrackingAblationCell& cell : cells) {
    const double n = std::max(1, cell.frames);
    cell.f_5mm /= n;
    cell.f_10mm /= n;
    cell.cd_sq_cm2 /= n;
    cell.cd_l1_cm /= n;
    cell.flip_share /= n;
    cell.rotation_error_deg /= n;
  }
  return cells;
}

}  // namespace doasido::synth
