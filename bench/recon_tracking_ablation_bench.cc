// The seed's tracking ablation (appendix Table 4) in kind, and what
// selection costs.
//
//   recon_tracking_ablation_bench [sequences] [server_sequences]   (default 50, 3)
//
// 1. {fixed, adaptive} pose guidance x {random, likelihood, clustering}
//    selection on synthetic sequences with occlusions, symmetric flips and
//    clutter (synth/tracking_scene.h): F-5, F-10 (higher is better), both
//    Chamfer distances (lower is better), per frame, averaged.
// 2. Selection time at N = 25 candidates, T = 25 Euler steps: clustering
//    (with silhouette IoU) against likelihood ranking, and each as a share
//    of the sampling time, with the analytic stand-in in process (a model
//    call costs microseconds) and through tools/velocity_server.py (the
//    same model behind the real protocol: every call a round trip to a
//    Python process, as with a network served the same way).
// 3. Threads over a frame's candidates (flow.threads 1 vs 2, in process):
//    sampling + selection seconds.
#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <vector>

#include "eval/mixture_file.h"
#include "eval/tracking_ablation.h"
#include "recon/track/object_tracker.h"
#include "recon/track/silhouette.h"
#include "recon/track/velocity_server.h"

namespace {

using namespace doasido;

// Sampling and selection seconds per frame through the reference server.
void ThroughTheServer(int sequences) {
  double seconds[2][2] = {{0, 0}, {0, 0}};  // [likelihood, clustering][sampling, selection]
  int frames = 0;
  const auto dir = std::filesystem::temp_directory_path() / "doasido-tracking-bench";
  std::filesystem::create_directories(dir);
  for (int s = 0; s < sequences; ++s) {
    const synth::TrackingScene scene = synth::MakeTrackingScene(100 + s);
    recon::WriteMixtureNpz(dir / "modes.npz", *scene.model);
    recon::VelocityServer server(std::string("/usr/bin/python3 ") + DOASIDO_SOURCE_DIR +
                                     "/tools/velocity_server.py " + (dir / "modes.npz").string(),
                                 dir / "server.log");
    const recon::SilhouetteRenderer renderer(scene.mesh);
    recon::TrackInputs inputs;
    inputs.pose_guidance.assign(scene.truth.size(), 0.5);
    inputs.silhouette_iou = [&](int k, const Pose& p) {
      return renderer.IoU(p, scene.camera, scene.masks[k], 2, scene.hand_masks[k]);
    };
    const int T = static_cast<int>(scene.truth.size());
    for (int m = 0; m < 2; ++m) {
      recon::PoseSelectionConfig selection;
      selection.method = m == 0 ? recon::kSelectLikelihood : recon::kSelectClustering;
      for (const auto& f : recon::TrackObject(server, T, inputs, {}, selection)) {
        seconds[m][0] += f.sampling_seconds;
        seconds[m][1] += f.selection_seconds;
      }
    }
    frames += T;
  }
  std::filesystem::remove_all(dir);
  std::printf("through tools/velocity_server.py (%d frames): sampling %.2f ms/frame; selection: "
              "likelihood %.2f ms/frame (%.2fx the sampling), clustering %.2f ms/frame (%.3fx the "
              "sampling); clustering is %.0fx faster\n",
              frames, 1e3 * seconds[1][0] / frames, 1e3 * seconds[0][1] / frames,
              seconds[0][1] / seconds[0][0], 1e3 * seconds[1][1] / frames,
              seconds[1][1] / seconds[1][0], seconds[0][1] / seconds[1][1]);
}

void Threads(int sequences) {
  double seconds[2] = {0, 0};
  for (int threads = 1; threads <= 2; ++threads) {
    synth::TrackingAblationOptions options;
    options.sequences = sequences;
    options.flow.threads = threads;
    for (const auto& c : synth::RunTrackingAblation(options)) {
      seconds[threads - 1] += c.sampling_seconds + c.selection_seconds;
    }
  }
  // That the tracks do not change is tested (recon_guided_flow_test); two
  // calls of the ablation in one process differ in their adaptive cells
  // even at one thread (a cause in the synthetic harness not found yet), so they are
  // not compared here.
  std::printf("threads over candidates (%d sequences, all six cells, in process): sampling + selection "
              "%.2f s on 1 thread, %.2f s on 2 (%.2fx)\n",
              sequences, seconds[0], seconds[1], seconds[0] / seconds[1]);
}

}  // namespace

int main(int argc, char** argv) {
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
  ThroughTheServer(argc > 2 ? std::atoi(argv[2]) : 3);
  Threads(std::min(options.sequences, 10));
  return 0;
}
