#include "recon/track/object_tracker.h"

#include <chrono>

#include "core/error.h"

namespace doasido::recon {
namespace {

using Clock = std::chrono::steady_clock;

PoseChoice Choose(VelocityField& model, int frame, const StateMatrix& states,
                  const std::vector<Pose>& poses, const TrackInputs& inputs,
                  const GuidedFlowConfig& flow, const PoseSelectionConfig& selection,
                  TaskPool& pool) {
  if (selection.method == kSelectRandom) {
    return SelectRandom(static_cast<int>(poses.size()), selection.seed, frame);
  }
  if (selection.method == kSelectLikelihood) {
    return SelectByLikelihood(PoseLogLikelihood(model, frame, states, flow.steps, &pool));
  }
  if (!inputs.silhouette_iou) {
    throw Error("bad_config", "clustering selection needs the object's mesh and masks");
  }
  return SelectByClustering(poses, selection,
                            [&](const Pose& p) { return inputs.silhouette_iou(frame, p); }, &pool);
}

}  // namespace

std::vector<TrackedFrame> TrackObject(VelocityField& model, int frames,
                                      const TrackInputs& inputs, const GuidedFlowConfig& flow,
                                      const PoseSelectionConfig& selection) {
  const FlowLayout layout = model.Layout();
  TaskPool pool(flow.threads);
  std::vector<TrackedFrame> out;
  GuidedTargets targets;
  targets.shape = Eigen::VectorXd::Zero(layout.shape_dim);
  targets.pose = Eigen::VectorXd::Zero(layout.pose_dim);
  for (int k = 0; k < frames; ++k) {
    // The anchor frame is the model's own unguided sample.
    targets.shape_guidance = k == 0 ? 0.0 : flow.shape_guidance;
    targets.pose_guidance =
        k == 0 ? 0.0 : (k < static_cast<int>(inputs.pose_guidance.size()) ? inputs.pose_guidance[k]
                                                                          : 0.0);
    const auto start = Clock::now();
    const StateMatrix states =
        SampleGuided(model, k, targets, flow.candidates, flow.steps, flow.seed, &pool);
    const auto sampled = Clock::now();
    TrackedFrame frame;
    frame.pose_guidance = targets.pose_guidance;
    for (Eigen::Index i = 0; i < states.rows(); ++i) {
      frame.candidates.push_back(PoseFromState(layout, states.row(i)));
    }
    frame.choice = Choose(model, k, states, frame.candidates, inputs, flow, selection, pool);
    frame.sampling_seconds = std::chrono::duration<double>(sampled - start).count();
    frame.selection_seconds = std::chrono::duration<double>(Clock::now() - sampled).count();
    frame.pose = frame.candidates[frame.choice.index];
    if (k == 0) targets.shape = states.row(frame.choice.index).head(layout.shape_dim).transpose();
    targets.pose = PoseBlock(frame.pose).transpose();
    out.push_back(std::move(frame));
  }
  return out;
}

}  // namespace doasido::recon
