// Accuracy of the seed's hand-object alignment (recon/align/hand_object_alignment.h)
// on synthetic clips with MoGe-like per-frame depth-scale error: the object
// translation as the pose model hands it in (in the point map's scale,
// t_model = s_t t_true: "unaligned", the peer) against the aligned
// translation, with and without the temporal smoothing; once with exact
// hands and once with HaWoR-like hand jitter. Prints the median
// object-translation error over all frames of all clips, in cm, and the
// ratio to the peer; then the same on a bundle built from the real HOT3D
// sample's poses (below).
//
//   recon_alignment_bench [clips=30] [scale_sigma=0.08] [smooth_weight=config default]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <sstream>
#include <vector>

#include <filesystem>
#include <map>


#include "core/mesh.h"
#include "eval/hot3d_recording.h"
#include "recon/align/hand_object_alignment.h"
#include "recon/ray_caster.h"
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

void Report(const char* label, const Errors& e) {
  const double u = Median(e.unaligned), a = Median(e.aligned), s = Median(e.smoothed);
  std::printf("%-30s frames %5zu/%5d (aligned by evidence %d) | median error cm: unaligned %6.3f"
              "  aligned %6.3f (%.2fx)  aligned+smoothing %6.3f (%.2fx) | s/clip %.2f, smoothed %.2f\n",
              label, e.aligned.size(), e.frames, e.aligned_frames, 100 * u, 100 * a, a / u,
              100 * s, s / u, e.seconds_aligned, e.seconds_smoothed);
}


// ---- HOT3D-derived bundle ------------------------------------------------
// Real poses from ../shared/data/hot3d_sample: the object nearest a hand
// (with its real GLB model), that hand's wrist trajectory (UmeTrack), the
// headset positions. A virtual pinhole camera at the headset looks at the
// hand-object midpoint each frame; the hand is a 9 x 8 x 3 cm box at the
// wrist pose (the UmeTrack mesh needs its skinning model, not in the
// sample). Depth and masks are ray cast with Embree, then corrupted like
// the synthetic clips.

using PoseTrack = std::map<long long, Pose>;

TriMesh HandBox() {
  TriMesh m;
  const Vec3 h(0.045, 0.04, 0.015);
  m.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) {
    m.vertices.row(i) << ((i & 1) ? h.x() : -h.x()), ((i >> 1 & 1) ? h.y() : -h.y()),
        ((i >> 2 & 1) ? h.z() : -h.z());
  }
  m.faces.resize(12, 3);
  m.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4,
      6, 1, 3, 5, 3, 7, 5;
  return m;
}

// Camera (world->camera) at `eye` looking at `target`; the roll does not
// matter to the alignment.
Pose LookAt(const Vec3& eye, const Vec3& target) {
  const Vec3 z = (target - eye).normalized();
  Vec3 x = z.cross(Vec3::UnitZ());
  if (x.norm() < 1e-6) x = z.cross(Vec3::UnitY());
  x.normalize();
  Mat3 r;
  r << x.transpose(), z.cross(x).transpose(), z.transpose();  // rows: camera axes in world
  return {Quat(r), -(r * eye)};
}

bool Hot3dBundle(const std::filesystem::path& root, recon::ClipBundle& b, std::string& label) {
  const auto rec = root / "Aria" / "P0003_c701bd11";
  if (!std::filesystem::exists(rec / "dynamic_objects.csv")) return false;
  const recon::Hot3dRecording recording = recon::ReadHot3dRecording(rec);
  const auto& objects = recording.objects;
  const auto headset = recon::ReadHot3dPoses(rec / "headset_trajectory.csv").begin()->second;
  std::map<std::string, PoseTrack> wrists;
  for (const auto& [side, poses] : recording.hands) {
    for (const auto& [stamp, p] : poses) wrists[side][stamp] = p.wrist;
  }
  // The (object with a model, hand) pair closest over the recording.
  double best = 1e30;
  std::string uid, hand;
  for (const auto& [o, track] : objects) {
    if (!std::filesystem::exists(root / "object_library" / (o + ".glb"))) continue;
    for (const auto& [h, wrist] : wrists) {
      std::vector<double> d;
      for (const auto& [stamp, p] : track) {
        if (auto it = wrist.find(stamp); it != wrist.end()) d.push_back((p.t - it->second.t).norm());
      }
      if (d.size() < 10) continue;
      const double m = Median(d);
      if (m < best) {
        best = m;
        uid = o;
        hand = h;
      }
    }
  }
  if (uid.empty()) return false;
  const TriMesh object = LoadMesh(root / "object_library" / (uid + ".glb"));
  const TriMesh box = HandBox();
  constexpr int kSize = 320;
  Mat3 K;
  K << 260, 0, 159.5, 0, 260, 159.5, 0, 0, 1;
  const Mat3 k_inv = K.inverse();
  b = {};
  b.width = b.height = kSize;
  b.K = {K};
  b.object_mesh = object;
  recon::HandTrack h;
  std::vector<long long> stamps;
  for (const auto& [stamp, world_object] : objects.at(uid)) {
    const auto w = wrists.at(hand).find(stamp);
    const auto e = headset.find(stamp);
    if (w == wrists.at(hand).end() || e == headset.end()) continue;
    stamps.push_back(stamp);
    const Pose cam = LookAt(e->second.t, 0.5 * (world_object.t + w->second.t));
    const Pose obj = cam * world_object;
    const TriMesh hand_mesh = box.Transformed(cam * w->second);
    const TriMesh obj_mesh = object.Transformed(obj);
    const recon::RayCaster hc(hand_mesh.vertices, hand_mesh.faces), oc(obj_mesh.vertices, obj_mesh.faces);
    cv::Mat depth(kSize, kSize, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
    cv::Mat mh = cv::Mat::zeros(kSize, kSize, CV_8U), mo = mh.clone();
    for (int v = 0; v < kSize; ++v) {
      for (int u = 0; u < kSize; ++u) {
        const Vec3 dir = (k_inv * Vec3(u, v, 1)).normalized();
        const auto a = hc.FirstHit(Vec3::Zero(), dir), o = oc.FirstHit(Vec3::Zero(), dir);
        const double da = a ? *a : 1e9, d_o = o ? *o : 1e9;
        if (std::min(da, d_o) > 1e8) continue;
        (da < d_o ? mh : mo).at<std::uint8_t>(v, u) = 255;
        depth.at<float>(v, u) = static_cast<float>(std::min(da, d_o) * dir.z());
      }
    }
    b.depth.push_back(depth);
    b.mask_hand_right.push_back(mh);
    b.mask_hand_left.push_back(cv::Mat::zeros(kSize, kSize, CV_8U));
    b.mask_object.push_back(mo);
    b.object_poses.push_back(obj);
    h.valid.push_back(true);
    recon::Joints21 j;
    j.rowwise() = (cam * w->second.t).transpose();
    h.joints.push_back(j);
    h.verts.push_back(hand_mesh.vertices);
    h.faces = hand_mesh.faces;
  }
  b.hand_right = h;
  b.frames = static_cast<int>(stamps.size());
  b.fps = 1e9 * (b.frames - 1) / static_cast<double>(stamps.back() - stamps.front());
  std::ostringstream l;
  l << "HOT3D obj " << uid << " hand " << hand << " (median wrist-object " << 100 * best
    << " cm)";
  label = l.str();
  return true;
}

// Corrupts `truth` like the models would (MoGe-like depth scale per frame
// and the object translation with it; HaWoR-like hands when asked), aligns
// with and without smoothing, and collects the translation errors.
enum class HandNoise { kNone, kJitterOnly, kFull };
const char* kHandNoiseName[] = {"exact hands", "HaWoR jitter, no bias", "HaWoR-like (full)"};

double g_smooth_weight = recon::HandObjectAlignmentConfig{}.smooth_weight;

void RunBundle(const recon::ClipBundle& truth, double scale_sigma, HandNoise hand_noise, int seed,
               Errors& e) {
  recon::ClipBundle b = truth;
  std::mt19937_64 rng(seed);
  for (cv::Mat& d : b.depth) d = d.clone();
  synth::DepthNoiseConfig depth_noise;
  depth_noise.scale_sigma = scale_sigma;
  const std::vector<double> s = synth::ApplyDepthNoise(b.depth, depth_noise, rng);
  if (hand_noise != HandNoise::kNone) {
    synth::HandNoiseConfig noise;  // per-joint noise, AR(1) jitter, per-clip depth bias
    if (hand_noise == HandNoise::kJitterOnly) noise.depth_sigma = 0;
    if (b.hand_left) synth::ApplyHandNoise(*b.hand_left, noise, rng);
    if (b.hand_right) synth::ApplyHandNoise(*b.hand_right, noise, rng);
  }
  std::vector<Pose> model;
  for (int t = 0; t < b.frames; ++t) model.push_back({b.object_poses[t].q, s[t] * b.object_poses[t].t});
  const std::vector<bool> valid(b.frames, true);
  recon::HandObjectAlignmentConfig config;
  config.smooth_weight = g_smooth_weight;
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
    const Vec3& gt = truth.object_poses[t].t;
    e.unaligned.push_back((model[t].t - gt).norm());
    e.aligned.push_back((a.poses[t].t - gt).norm());
    e.smoothed.push_back((m.poses[t].t - gt).norm());
  }
}
}  // namespace
}  // namespace doasido

int main(int argc, char** argv) {
  using namespace doasido;
  const int clips = argc > 1 ? std::atoi(argv[1]) : 30;
  const double sigma = argc > 2 ? std::atof(argv[2]) : 0.08;
  if (argc > 3) g_smooth_weight = std::atof(argv[3]);
  synth::SynthConfig cfg;
  cfg.width = 320;
  cfg.height = 240;
  cfg.frames = 30;
  cfg.seed = 11;
  std::printf("recon_alignment_bench: %d synthetic clean clips, %dx%d, %d frames, MoGe-like "
              "per-frame scale sigma %.3f (log), pixel noise 1%%, smooth_weight %.3g\n",
              clips, cfg.width, cfg.height, cfg.frames, sigma, g_smooth_weight);
  const HandNoise modes[] = {HandNoise::kNone, HandNoise::kJitterOnly, HandNoise::kFull};
  for (HandNoise hand_noise : modes) {
    Errors e;
    for (int i = 0; i < clips; ++i) {
      const auto clip = synth::RenderClip(cfg, i, synth::DefectKind::kClean);
      RunBundle(clip.bundle, sigma, hand_noise, 1000 + i, e);
    }
    e.seconds_aligned /= clips;
    e.seconds_smoothed /= clips;
    Report(kHandNoiseName[static_cast<int>(hand_noise)], e);
  }
  recon::ClipBundle hot3d;
  std::string label;
  if (!Hot3dBundle(DOASIDO_SHARED_DATA "/hot3d_sample", hot3d, label)) {
    std::printf("HOT3D sample not found: skipped\n");
    return 0;
  }
  std::printf("%s: %d frames at %.1f fps; 10 noise draws\n", label.c_str(), hot3d.frames, hot3d.fps);
  for (HandNoise hand_noise : modes) {
    Errors e;
    for (int draw = 0; draw < 10; ++draw) RunBundle(hot3d, sigma, hand_noise, 500 + draw, e);
    e.seconds_aligned /= 10;
    e.seconds_smoothed /= 10;
    Report((std::string("HOT3D ") + kHandNoiseName[static_cast<int>(hand_noise)]).c_str(), e);
  }
  return 0;
}
