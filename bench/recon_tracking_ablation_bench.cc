// The seed's tracking ablation (appendix Table 4) in kind, and what
// selection costs.
//
//   recon_tracking_ablation_bench [sequences]     (default 50)
//
// 1. {fixed, adaptive} pose guidance x {random, likelihood, clustering}
//    selection on synthetic sequences with occlusions, symmetric flips and
//    clutter (synth/tracking_scene.h): F-5, F-10 (higher is better), both
//    Chamfer distances (lower is better), per frame, averaged.
// 2. Selection time at N = 25 candidates, T = 25 Euler steps: clustering
//    (with silhouette IoU) against likelihood ranking, and each as a share
//    of the sampling time. With the analytic stand-in a model call costs
//    microseconds; the model-call counts say what the ratio becomes with a
//    network that dominates every call.
#include <cstdio>
#include <cstdlib>

#include "synth/tracking_ablation.h"

int main(int argc, char** argv) {
  using namespace doasido;
  synth::TrackingAblationOptions options;
  if (argc > 1) options.sequences = std::atoi(argv[1]);
  const auto cells = synth::RunTrackingAblation(options);
  std::printf("tracking ablation: %d sequences x %d frames, N = %d, T = %d, fixed alpha_p = %.2f\n",
              options.sequences, options.scene.frames, options.flow.candidates,
              options.flow.steps, options.fixed_pose_guidance);
  std::printf("%-9s %-11s %6s %6s %10s %9s %7s %6s %12s %13s %9s\n", "guidance", "selection",
              "F-5", "F-10", "CD cm^2", "CD-L1 cm", "rot deg", "flips", "sampling s",
              "selection s", "sel/samp");
  double clustering_s = 0, likelihood_s = 0, frames = 0;
  for (const auto& c : cells) {
    std::printf("%-9s %-11s %6.3f %6.3f %10.3f %9.3f %7.2f %6.3f %12.3f %13.3f %9.3f\n",
                c.guidance.c_str(), c.selection.c_str(), c.f_5mm, c.f_10mm, c.cd_sq_cm2,
                c.cd_l1_cm, c.rotation_error_deg, c.flip_share, c.sampling_seconds,
                c.selection_seconds, c.selection_seconds / c.sampling_seconds);
    if (c.selection == "clustering") clustering_s += c.selection_seconds;
    if (c.selection == "likelihood") likelihood_s += c.selection_seconds;
    frames += c.frames;
  }
  const int T = options.flow.steps, D = 7;
  std::printf("selection per frame: clustering %.3f ms, likelihood %.3f ms (ratio %.1fx)\n",
              1e3 * clustering_s / (frames / 6), 1e3 * likelihood_s / (frames / 6),
              likelihood_s / clustering_s);
  std::printf("model calls per frame (batched over N): sampling %d, likelihood %d velocity + %d "
              "divergence = %d backbone passes with exact traces (1 + %d per step), clustering 0\n",
              T, T, T, T * (1 + D), D);
  return 0;
}
