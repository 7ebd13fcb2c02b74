// Accuracy of the seed's hand-object alignment (recon/hand_object_alignment.h)
// on synthetic clips with MoGe-like per-frame depth-scale error: the object
// translation as the pose model hands it in (in the point map's scale,
// t_model = s_t t_true: "unaligned", the peer) against the aligned
// translation, with and without the temporal smoothing; once with exact
// hands and once with HaWoR-like hand jitter. Prints the median
// object-translation error over all frames of all clips, in cm, and the
// ratio to the peer.
//
//   recon_alignment_bench [clips=30] [scale_sigma=0.08]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "recon/hand_object_alignment.h"
#include "synth/generator.h"
#include "synth/model_noise.h"

namespace doasido {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct Errors {
  std::vector<double> unaligned, aligned, smoothed;
  double seconds_aligned = 0, seconds_smoothed = 0;
  int frames = 0, aligned_frames = 0;
};

void RunClip(const synth::SynthConfig& cfg, int index, double scale_sigma, bool hand_noise,
             Errors& e) {
  const synth::RenderedClip clip = synth::RenderClip(cfg, index, synth::DefectKind::kClean);
  recon::ClipBundle b = clip.bundle;
  std::mt19937_64 rng(1000 + index);
  for (cv::Mat& d : b.depth) d = d.clone();
  synth::DepthNoiseConfig depth_noise;
  depth_noise.scale_sigma = scale_sigma;
  const std::vector<double> s = synth::ApplyDepthNoise(b.depth, depth_noise, rng);
  if (hand_noise) {
    if (b.hand_left) synth::ApplyHandNoise(*b.hand_left, {}, rng);
    if (b.hand_right) synth::ApplyHandNoise(*b.hand_right, {}, rng);
  }
  std::vector<Pose> model;
  for (int t = 0; t < b.frames; ++t) {
    model.push_back({b.object_poses[t].q, s[t] * b.object_poses[t].t});
  }
  const std::vector<bool> valid(b.frames, true);
  recon::HandObjectAlignmentConfig config;
  auto start = std::chrono::steady_clock::now();
  const auto a = recon::AlignHandObject(b, model, valid, config);
  e.seconds_aligned += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  config.smooth = true;
  start = std::chrono::steady_clock::now();
  const auto m = recon::AlignHandObject(b, model, valid, config);
  e.seconds_smoothed += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  e.frames += b.frames;
  e.aligned_frames += a.aligned_frames;
  for (int t = 0; t < b.frames; ++t) {
    // Frames no method can place (no scale) count for none of the three.
    if (!std::isfinite(a.scale[t]) || !std::isfinite(m.scale[t])) continue;
    const Vec3& truth = clip.bundle.object_poses[t].t;
    e.unaligned.push_back((model[t].t - truth).norm());
    e.aligned.push_back((a.poses[t].t - truth).norm());
    e.smoothed.push_back((m.poses[t].t - truth).norm());
  }
}

void Report(const char* label, const Errors& e) {
  const double u = Median(e.unaligned), a = Median(e.aligned), s = Median(e.smoothed);
  std::printf("%-22s frames %5zu/%5d (aligned by evidence %d) | median error cm: unaligned %6.3f"
              "  aligned %6.3f (%.2fx)  aligned+smoothing %6.3f (%.2fx) | s/clip %.2f vs %.2f\n",
              label, e.aligned.size(), e.frames, e.aligned_frames, 100 * u, 100 * a, a / u,
              100 * s, s / u, e.seconds_aligned, e.seconds_smoothed);
}

}  // namespace
}  // namespace doasido

int main(int argc, char** argv) {
  using namespace doasido;
  const int clips = argc > 1 ? std::atoi(argv[1]) : 30;
  const double sigma = argc > 2 ? std::atof(argv[2]) : 0.08;
  synth::SynthConfig cfg;
  cfg.width = 320;
  cfg.height = 240;
  cfg.frames = 30;
  cfg.seed = 11;
  std::printf("recon_alignment_bench: %d synthetic clean clips, %dx%d, %d frames, MoGe-like "
              "per-frame scale sigma %.3f (log), pixel noise 1%%\n",
              clips, cfg.width, cfg.height, cfg.frames, sigma);
  for (bool hand_noise : {false, true}) {
    Errors e;
    for (int i = 0; i < clips; ++i) RunClip(cfg, i, sigma, hand_noise, e);
    e.seconds_aligned /= clips;
    e.seconds_smoothed /= clips;
    Report(hand_noise ? "HaWoR-like hands" : "exact hands", e);
  }
  return 0;
}
