// The hands stage measured (docs/hands.md quotes the figures):
//   hands_bench real [frames]  the bundled positive clips: fitted palm width
//                              (adult hands: 7-10 cm), the largest wrist
//                              jump between frames, frames with a hand, and
//                              CPU seconds per second of video for detection
//                              (the models' process included) and the fit
//                              (and the fit trusting every frame).
//   hands_bench dex [frames]   retarget/human_hand_video.mp4 against the
//                              keypoints dex-retargeting's example pipeline
//                              made of it (a peer's output, not ground
//                              truth): wrist-centred joint distance after the
//                              best rotation, and after rotation and scale.
//   hands_bench synth [clips]  synthetic tracks and rendered clips with exact
//                              hands: camera-frame MPJPE and wrist error after
//                              the fit, with the true K and with the default
//                              field of view, with the model's own size and
//                              with the adult size prior, and that prior
//                              without the world-landmark prior
//                              (fit.world_prior false; 0 clips: tracks only).
//   hands_bench labels         PCK at 0.1 and 0.2 of the hand box against the
//                              hand-made labels in bench/hand_labels/*.json
//                              (hands/hand_labels.h), for the models alone,
//                              the tracker and the fit; missed hands of each,
//                              left/right swaps of the models and the tracker,
//                              the mean 2D error (px) of the hands each found;
//                              the fit with every frame trusted beside it.
//   hands_bench startup [0|1]  the start-up tax of a fresh process, with (1)
//                              or without the graphs prepared before the
//                              first clip: models' ms per sample of three
//                              runs of one clip, graph pairs built.
//   hands_bench stills         stills made from the labelled frames (frame,
//                              gray, close-up, close-up gray;
//                              hands/labelled_stills.h): hands found, PCK@0.2
//                              and 0.1, 2D error, before and after the wide
//                              search (HandLandmarker::DetectStill), per
//                              video and kind.
//   hands_bench photos         the same for the labelled photos alone, per
//                              photo, per source package and per kind.
//   hands_bench jumps [frames] per side of each bundled positive, with every
//                              frame trusted and as the stage runs (untrusted
//                              frames, hands/hand_outliers.h): the largest
//                              wrist move and palm turn between frames; then
//                              the largest moves and what PnP did there.
// [frames] limits each video to its first frames (default: all); a third
// argument picks the hand models ([hands] models: full, lite, lite_landmark),
// a fourth keeps a tracked hand's keypoints where its crop barely changed
// (HandLandmarkerOptions::unchanged_crop_fraction; not a [hands] option), a
// fifth sets [hands] wide_search_every (0: the wide search on stills only).
#include <dirent.h>
#include <sys/resource.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/log.h"
#include "filters/hand_models.h"
#include "hands/hand_detection.h"
#include "hands/hand_labels.h"
#include "hands/hand_outliers.h"
#include "hands/hand_reconstruction.h"
#include "hands/labelled_stills.h"
#include "synth/generator.h"
#include "testing/synthetic_hand_track.h"

using namespace doasido;
using namespace doasido::hands;

namespace {

const std::string kData = DOASIDO_SHARED_DATA;

// CPU seconds of this process and of its live children (the models' Node
// process), from /proc: children still running are not in RUSAGE_CHILDREN.
double CpuSeconds() {
  rusage self{};
  getrusage(RUSAGE_SELF, &self);
  double s = self.ru_utime.tv_sec + self.ru_utime.tv_usec * 1e-6 + self.ru_stime.tv_sec +
             self.ru_stime.tv_usec * 1e-6;
  const long tick = sysconf(_SC_CLK_TCK);
  DIR* proc = opendir("/proc");
  while (dirent* e = proc ? readdir(proc) : nullptr) {
    if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
    std::ifstream in(std::string("/proc/") + e->d_name + "/stat");
    std::string stat;
    std::getline(in, stat);
    const size_t close = stat.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(stat.substr(close + 2));
    std::string state;
    long ppid = 0;
    rest >> state >> ppid;
    if (ppid != getpid()) continue;
    std::string skip;
    for (int i = 0; i < 9; ++i) rest >> skip;  // fields 6..14 up to utime
    long utime = 0, stime = 0;
    rest >> utime >> stime;
    s += static_cast<double>(utime + stime) / tick;
  }
  if (proc) closedir(proc);
  return s;
}

std::string g_models = HandsConfig{}.models;  // the third argument
// The fourth: HandLandmarkerOptions::unchanged_crop_fraction (0: off, the
// hands stage's behaviour), to measure keeping a still hand's keypoints.
double g_unchanged_crop = 0;
// The fifth: [hands] wide_search_every (the wide search on video frames
// without a tracked hand; 0: stills only).
int g_wide_every = HandsConfig{}.wide_search_every;

filters::HandLandmarkerOptions LandmarkerOptions(int wide_every) {
  return {.max_hands = HandsConfig{}.max_hands,
          .max_side = HandsConfig{}.max_side,
          .models = g_models,
          .palm_every = HandsConfig{}.palm_every,
          .lost_search = HandsConfig{}.palm_every,
          .unchanged_crop_fraction = g_unchanged_crop,
          .wide_every = wide_every,
          .lost_wide = HandsConfig{}.lost_wide_search};
}

filters::HandLandmarker& Landmarker() {
  static filters::HandLandmarker landmarker(LandmarkerOptions(g_wide_every));
  return landmarker;
}

// As the stage was before the wide search (issue 54): the palm detector only.
filters::HandLandmarker& PalmOnlyLandmarker() {
  static filters::HandLandmarker landmarker(LandmarkerOptions(0));
  return landmarker;
}

struct Run {
  DetectedFrames detected;
  HandsResult result;
  double detect_cpu = 0, fit_cpu = 0;
};

Run RunVideo(const std::string& path, std::int64_t frames, const Intrinsics* given = nullptr,
             const HandsConfig& config = HandsConfig{}) {
  Run r;
  DecoderOptions span{.last_frame = frames > 0 ? frames - 1 : -1, .clip = path};
  const double c0 = CpuSeconds();
  r.detected = DetectVideo(path, span, HandsConfig{}.max_side, Landmarker());
  const double c1 = CpuSeconds();
  const Intrinsics in = given ? *given
                              : Intrinsics{.K = KFromFov(r.detected.width, r.detected.height,
                                                         HandsConfig{}.default_fov_deg),
                                           .assumed = true,
                                           .source = kIntrinsicsFromDefault};
  r.result = ReconstructHands(r.detected, in, config);
  r.detect_cpu = c1 - c0;
  r.fit_cpu = CpuSeconds() - c1;
  return r;
}

// Jitter where the hand is still (fitted wrist slower than 5 cm/s): mean
// keypoint acceleration in px/frame^2 of the models' keypoints and of the
// fitted joints' projection, over frames whose neighbours are observed too.
struct Jitter {
  double raw = 0, fit = 0;
  int frames = 0;
};

void AddJitter(const FittedTrack& t, const Mat3& K, double fps, Jitter& j) {
  const Camera cam = Camera::FromK(K, 0, 0);
  for (size_t f = 1; f + 1 < t.joints.size(); ++f) {
    if (!t.observations[f - 1] || !t.observations[f] || !t.observations[f + 1]) continue;
    if ((t.joints[f + 1][0] - t.joints[f - 1][0]).norm() * fps / 2 > 0.05) continue;
    double raw = 0, fit = 0;
    for (int k = 0; k < kJoints; ++k) {
      raw += (t.observations[f + 1]->uv[k] - 2 * t.observations[f]->uv[k] +
              t.observations[f - 1]->uv[k])
                 .norm();
      fit += (cam.Project(t.joints[f + 1][k]) - 2 * cam.Project(t.joints[f][k]) +
              cam.Project(t.joints[f - 1][k]))
                 .norm();
    }
    j.raw += raw / kJoints;
    j.fit += fit / kJoints;
    ++j.frames;
  }
}

void Real(std::int64_t frames) {
  // The five bundled positives and asl_hand, the sixth video with hand-made
  // labels (its jitter belongs beside its PCK).
  const char* clips[] = {"02_cups.mp4", "03_blocks.mp4", "bass_guitar.mp4", "eyeliner.avi",
                         "laptop_trackpad.mp4", "asl_hand.mp4"};
  std::printf("%-20s %6s %6s %8s %8s %9s %28s %28s %8s %s\n", "clip", "frames", "hand%",
              "det cpu/s", "fit cpu/s", "total/s", "right palm cm med [min,max]",
              "left palm cm med [min,max]", "jump cm",
              "still: jitter px/f^2 models -> fit (frames); model's own palm cm; fit cpu/s "
              "trusting every frame");
  for (const char* clip : clips) {
    const Run r = RunVideo(kData + "/videos/" + clip, frames);
    const double video_s = r.detected.frames.size() / r.detected.fps;
    int with_hand = 0;
    for (const auto& f : r.detected.frames) with_hand += f.empty() ? 0 : 1;
    std::vector<double> model_palms;  // the landmark model's own 3D, observed frames
    for (const FittedTrack& t : r.result.tracks) {
      for (const auto& o : t.observations) {
        if (o) model_palms.push_back(100 * PalmWidth(o->world));
      }
    }
    std::sort(model_palms.begin(), model_palms.end());
    const double model_palm = model_palms.empty() ? 0.0 : model_palms[model_palms.size() / 2];
    std::string palms[2];
    double jump = 0;
    Jitter jitter;
    for (const FittedTrack& t : r.result.tracks)
      AddJitter(t, r.result.intrinsics.K, r.detected.fps, jitter);
    for (Side side : {Side::kRight, Side::kLeft}) {
      std::vector<double> w;
      // The wrist per side as the bundle holds it (hands.npz): a move between
      // two tracks of one side on consecutive frames counts too.
      std::vector<std::optional<Vec3>> wrist(r.detected.frames.size());
      for (const FittedTrack& t : r.result.tracks) {
        if (t.side != side) continue;
        for (size_t f = 0; f < t.joints.size(); ++f) {
          w.push_back(100 * PalmWidth(t.joints[f]));
          wrist[t.first_frame + f] = t.joints[f][0];
        }
      }
      for (size_t f = 1; f < wrist.size(); ++f) {
        if (wrist[f] && wrist[f - 1])
          jump = std::max(jump, 100 * (*wrist[f] - *wrist[f - 1]).norm());
      }
      char buf[64] = "-";
      if (!w.empty()) {
        std::sort(w.begin(), w.end());
        std::snprintf(buf, sizeof buf, "%.1f [%.1f, %.1f] n=%zu", w[w.size() / 2], w.front(),
                      w.back(), w.size());
      }
      palms[side == Side::kRight ? 0 : 1] = buf;
    }
    // The fit again on the same detection with every frame trusted
    // (hands/hand_outliers.h off): what the outlier checks cost.
    HandsConfig trusting;
    trusting.fit.max_untrusted_run = 0;
    const double c0 = CpuSeconds();
    ReconstructHands(r.detected, r.result.intrinsics, trusting);
    const double trusting_fit = CpuSeconds() - c0;
    std::printf(
        "%-20s %6zu %5.0f%% %8.2f %9.3f %9.2f %28s %28s %8.2f %.2f -> %.2f (%d); %.1f; fit "
        "trusting every frame %.3f\n",
        clip, r.detected.frames.size(), 100.0 * with_hand / r.detected.frames.size(),
        r.detect_cpu / video_s, r.fit_cpu / video_s, (r.detect_cpu + r.fit_cpu) / video_s,
        palms[0].c_str(), palms[1].c_str(), jump, jitter.frames ? jitter.raw / jitter.frames : 0.0,
        jitter.frames ? jitter.fit / jitter.frames : 0.0, jitter.frames, model_palm,
        trusting_fit / video_s);
    std::fflush(stdout);
  }
}

// Mean distance between wrist-centred joint sets after the best rotation
// (and scale, when `scale`) of `a` onto `b` (Umeyama).
double AlignedError(const Joints& a, const Joints& b, bool scale) {
  Eigen::Matrix<double, 3, kJoints> A, B;
  for (int j = 0; j < kJoints; ++j) {
    A.col(j) = a[j] - a[0];
    B.col(j) = b[j] - b[0];
  }
  const Eigen::Matrix4d T = Eigen::umeyama(A, B, scale);
  const Eigen::Matrix<double, 3, kJoints> C =
      (T.topLeftCorner<3, 3>() * A).colwise() + T.topRightCorner<3, 1>();
  return (C - B).colwise().norm().mean();
}

void Dex(std::int64_t frames) {
  const auto dex = testing::ReadDexKeypoints(kData + "/retarget/human_hand_keypoints_right.csv");
  const Run r = RunVideo(kData + "/retarget/human_hand_video.mp4", frames);
  double fit_r = 0, fit_rs = 0, pnp_r = 0, model_r = 0;
  int n = 0, swaps = 0;
  for (const FittedTrack& t : r.result.tracks) {
    if (t.side != Side::kRight) ++swaps;
    for (size_t f = 0; f < t.joints.size(); ++f) {
      const size_t frame = t.first_frame + f;
      if (frame >= dex.size() || !t.has_pnp[f]) continue;
      fit_r += AlignedError(t.joints[f], dex[frame], false);
      fit_rs += AlignedError(t.joints[f], dex[frame], true);
      pnp_r += AlignedError(t.pnp_joints[f], dex[frame], false);
      model_r += AlignedError(t.observations[f]->world, dex[frame], false);
      ++n;
    }
  }
  std::printf("human_hand_video.mp4: %zu frames, %d compared, %zu tracks (%d not right)\n",
              r.detected.frames.size(), n, r.result.tracks.size(), swaps);
  std::printf("mean joint distance to dex-retargeting's keypoints, wrist-centred:\n");
  std::printf("  landmark model's 3D, best rotation      %.2f cm\n", 100 * model_r / n);
  std::printf("  PnP (before the fit), best rotation      %.2f cm\n", 100 * pnp_r / n);
  std::printf("  fitted skeleton, best rotation           %.2f cm\n", 100 * fit_r / n);
  std::printf("  fitted skeleton, best rotation and scale %.2f cm\n", 100 * fit_rs / n);
}

// Error of a fitted track against the nearer rendered hand, frame by frame:
// sums of MPJPE and wrist error; frames where that hand is the other side
// count as side errors.
struct SynthError {
  double mpjpe = 0, root = 0;
  int frames = 0, other_side = 0;
};

void Score(const FittedTrack& t, const recon::ClipBundle& b, SynthError& e) {
  for (size_t f = 0; f < t.joints.size(); ++f) {
    const size_t g = t.first_frame + f;
    double best = 1e9, root = 0;
    bool same_side = true;
    for (Side side : {Side::kRight, Side::kLeft}) {
      const auto& hand = side == Side::kRight ? b.hand_right : b.hand_left;
      if (!hand || !hand->valid[g]) continue;
      double sum = 0;
      for (int j = 0; j < kJoints; ++j)
        sum += (t.joints[f][j] - hand->joints[g].row(j).transpose()).norm();
      if (sum / kJoints < best) {
        best = sum / kJoints;
        root = (t.joints[f][0] - hand->joints[g].row(0).transpose()).norm();
        same_side = side == t.side;
      }
    }
    if (best > 1e8) continue;
    e.mpjpe += best;
    e.root += root;
    ++e.frames;
    if (!same_side) ++e.other_side;
  }
}

void PrintError(const char* name, const SynthError& e) {
  std::printf("  %-28s MPJPE %.2f cm, wrist %.2f cm over %d frames; %d on the other side\n", name,
              e.frames ? 100 * e.mpjpe / e.frames : 0.0, e.frames ? 100 * e.root / e.frames : 0.0,
              e.frames, e.other_side);
}

// Rendered clips (synth/): the models on the synthetic world's hands.
void SynthRendered(int clips) {
  synth::SynthConfig cfg;
  cfg.frames = 48;
  cfg.seed = 11;
  SynthError errors[4];  // [K][world prior on, off]
  HandsConfig no_world;
  no_world.fit.world_prior = false;
  int truth_hand_frames = 0;
  for (int i = 0; i < clips; ++i) {
    const synth::RenderedClip clip = synth::RenderClip(cfg, i, synth::DefectKind::kClean);
    const recon::ClipBundle& b = clip.bundle;
    DetectedFrames d;
    d.width = b.width;
    d.height = b.height;
    d.fps = b.fps;
    Landmarker().Reset();
    for (const cv::Mat& bgr : clip.bgr) {
      FrameObservations hands;
      for (const auto& h : Landmarker().Detect(bgr))
        hands.push_back(FromLandmarked(h, 1.0, d.width, d.height));
      d.frames.push_back(hands);
    }
    for (const auto* hand : {&b.hand_right, &b.hand_left}) {
      if (*hand)
        truth_hand_frames +=
            static_cast<int>(std::count((*hand)->valid.begin(), (*hand)->valid.end(), true));
    }
    const Intrinsics variants[2] = {
        {.K = b.KAt(0), .assumed = false, .source = "truth"},
        {.K = KFromFov(b.width, b.height, HandsConfig{}.default_fov_deg),
         .assumed = true,
         .source = kIntrinsicsFromDefault}};
    for (int v = 0; v < 4; ++v) {
      for (const FittedTrack& t :
           ReconstructHands(d, variants[v / 2], v % 2 ? no_world : HandsConfig{}).tracks)
        Score(t, b, errors[v]);
    }
  }
  std::printf("rendered clips: %d clips, %d hand-frames in the truth\n", clips, truth_hand_frames);
  PrintError("true K", errors[0]);
  PrintError("true K, no world prior", errors[1]);
  PrintError("default fov", errors[2]);
  PrintError("default fov, no world prior", errors[3]);
}

// Synthetic tracks (testing/synthetic_hand_track.h): a real hand's motion
// seen through cameras of three focal lengths, keypoints with 1.5 px noise,
// 3D landmarks with 3 mm noise; fitted with the true K and the default
// fov, each with the model's own size (the synthetic landmarks have the
// true size) and with the adult size prior (the default; the synthetic
// hand is 0.190 m long, the prior's centre 0.182 m).
void SynthTracks() {
  const auto rows = testing::ReadDexKeypoints(kData + "/retarget/human_hand_keypoints_right.csv");
  std::printf("synthetic tracks: 8 x 90 frames per camera, 1.5 px and 3 mm noise\n");
  FitConfig model_size;
  model_size.size_prior = "model";
  FitConfig no_world;
  no_world.world_prior = false;
  constexpr int kFits = 3;
  const FitConfig fits[kFits] = {model_size, FitConfig{}, no_world};
  const char* fit_names[kFits] = {"model size", "adult prior", "adult, no world prior"};
  int untrusted = 0;  // untrusted frames (hands/hand_outliers.h), true K, model size
  for (double fx : {400.0, 500.0, 700.0}) {
    SynthError errors[2 * kFits + 1];  // [K][fit] as kFits k + f; the last: PnP only
    for (int k = 0; k < 8; ++k) {
      const auto h = testing::MakeSyntheticHand(rows, 90, 60 * k, 1.5, 0.003, 0.9, 100 + k, fx);
      std::vector<FrameObservations> frames;
      for (const auto& o : h.seen) frames.push_back({o});
      const auto tracks = BuildTracks(frames, TrackerConfig{});
      const Mat3 Ks[2] = {h.K, KFromFov(h.width, h.height, HandsConfig{}.default_fov_deg)};
      for (int v = 0; v < 2 * kFits; ++v) {
        for (const Track& tr : tracks) {
          const FittedTrack fit = FitTrack(tr, Ks[v / kFits], h.fps, fits[v % kFits]);
          if (v == 0) untrusted += fit.untrusted_frames;
          for (size_t f = 0; f < fit.joints.size(); ++f) {
            for (int pnp = 0; pnp < (v == 0 ? 2 : 1); ++pnp) {
              if (pnp && !fit.has_pnp[f]) continue;
              SynthError& e = errors[pnp ? 2 * kFits : v];
              const Joints& x = pnp ? fit.pnp_joints[f] : fit.joints[f];
              double sum = 0;
              for (int j = 0; j < kJoints; ++j)
                sum += (x[j] - h.truth[fit.first_frame + f][j]).norm();
              e.mpjpe += sum / kJoints;
              e.root += (x[0] - h.truth[fit.first_frame + f][0]).norm();
              ++e.frames;
            }
          }
        }
      }
    }
    const double fov = 2 * std::atan(320 / fx) * 180 / M_PI;
    char name[64];
    std::snprintf(name, 64, "fx %.0f (%.0f deg), true K, PnP only", fx, fov);
    PrintError(name, errors[2 * kFits]);
    for (int v = 0; v < 2 * kFits; ++v) {
      std::snprintf(name, 64, "fx %.0f, %s, %s", fx, v / kFits ? "default 65 deg" : "true K",
                    fit_names[v % kFits]);
      PrintError(name, errors[v]);
    }
  }
  std::printf("untrusted frames (true K, model size): %d\n", untrusted);
}

void Synth(int clips) {
  SynthTracks();
  if (clips > 0) SynthRendered(clips);
}

}  // namespace

double BoxSize(const HandObservation& o) {
  Eigen::Vector2d lo = o.uv[0], hi = o.uv[0];
  for (const auto& p : o.uv) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

// One side's wrist steps between consecutive frames as hands.npz holds
// them (across tracks too): the largest move (cm) and palm turn (degrees,
// HandTurnDeg), steps turning over 20 degrees, valid and untrusted frames.
struct SideSteps {
  double move_cm = 0, turn_deg = 0;
  int over_20 = 0, valid = 0, untrusted = 0;
  int move_at = -1, turn_at = -1;  // the later frame of each
};

SideSteps Steps(const HandsResult& result, Side side, size_t frames) {
  SideSteps s;
  std::vector<const Joints*> at(frames, nullptr);
  for (const FittedTrack& t : result.tracks) {
    if (t.side != side) continue;
    for (size_t f = 0; f < t.joints.size(); ++f) {
      at[t.first_frame + f] = &t.joints[f];
      ++s.valid;
      s.untrusted += t.untrusted[f] ? 1 : 0;
    }
  }
  for (size_t f = 1; f < frames; ++f) {
    if (!at[f] || !at[f - 1]) continue;
    const double move = 100 * ((*at[f])[0] - (*at[f - 1])[0]).norm();
    const double turn = HandTurnDeg(*at[f - 1], *at[f]);
    s.over_20 += turn > 20 ? 1 : 0;
    if (move > s.move_cm) {
      s.move_cm = move;
      s.move_at = static_cast<int>(f);
    }
    if (turn > s.turn_deg) {
      s.turn_deg = turn;
      s.turn_at = static_cast<int>(f);
    }
  }
  return s;
}

// The largest wrist moves inside the tracks of `result`, with what the
// models and PnP did there: the 2D wrist move and the keypoint box's size
// change, PnP's wrist depth and turn between the two frames.
void PrintLargestMoves(const HandsResult& result) {
  struct J {
    double cm;
    int track, frame;
  };
  std::vector<J> jumps;
  for (size_t k = 0; k < result.tracks.size(); ++k) {
    const FittedTrack& t = result.tracks[k];
    for (size_t f = 1; f < t.joints.size(); ++f) {
      jumps.push_back({100 * (t.joints[f][0] - t.joints[f - 1][0]).norm(), static_cast<int>(k),
                       static_cast<int>(f)});
    }
  }
  std::sort(jumps.begin(), jumps.end(), [](const J& a, const J& b) { return a.cm > b.cm; });
  for (size_t i = 0; i < std::min<size_t>(3, jumps.size()); ++i) {
    const FittedTrack& t = result.tracks[jumps[i].track];
    const int f = jumps[i].frame;
    const auto &a = t.observations[f - 1], &b = t.observations[f];
    std::printf("    %.1f cm at %d->%d (track %d, %s, %zu frames): fit z %.1f -> %.1f cm;",
                jumps[i].cm, t.first_frame + f - 1, t.first_frame + f, jumps[i].track,
                SideName(t.side), t.joints.size(), 100 * t.joints[f - 1][0].z(),
                100 * t.joints[f][0].z());
    if (a && b) {
      std::printf(" 2D wrist %.0f px, box %.0f -> %.0f px, score %.2f -> %.2f;",
                  (b->uv[0] - a->uv[0]).norm(), BoxSize(*a), BoxSize(*b), a->score, b->score);
    } else {
      std::printf(" filled;");
    }
    if (t.has_pnp[f - 1] && t.has_pnp[f]) {
      std::printf(" PnP z %.1f -> %.1f cm, turn %.0f deg", 100 * t.pnp_joints[f - 1][0].z(),
                  100 * t.pnp_joints[f][0].z(), HandTurnDeg(t.pnp_joints[f - 1], t.pnp_joints[f]));
    }
    std::printf("\n");
  }
}

// The wrist steps of each bundled positive with every frame trusted
// (max_untrusted_run = 0, the stage before the check) and as the stage
// runs, on one detection; then the stage's largest moves inside a track
// with what the models and PnP did there.
void Jumps(std::int64_t frames) {
  const char* clips[] = {"02_cups.mp4", "03_blocks.mp4", "bass_guitar.mp4", "eyeliner.avi",
                         "laptop_trackpad.mp4"};
  std::printf(
      "per side: valid frames (untrusted filled), largest move cm @frame, largest palm "
      "turn deg @frame, steps over 20 deg\n");
  for (const char* clip : clips) {
    HandsConfig trusting;
    trusting.fit.max_untrusted_run = 0;
    Run r = RunVideo(kData + "/videos/" + clip, frames, nullptr, trusting);
    const HandsResult before = r.result;
    r.result = ReconstructHands(r.detected, before.intrinsics, HandsConfig{});
    std::printf("%s: %zu tracks\n", clip, r.result.tracks.size());
    for (Side side : {Side::kRight, Side::kLeft}) {
      for (const auto& [name, res] :
           {std::pair<const char*, const HandsResult*>{"before", &before},
            std::pair<const char*, const HandsResult*>{"after", &r.result}}) {
        const SideSteps s = Steps(*res, side, r.detected.frames.size());
        if (s.valid == 0) continue;
        std::printf("  %-5s %-6s %3d (%2d)  move %5.1f @%3d  turn %5.1f @%3d  >20: %d\n",
                    SideName(side), name, s.valid, s.untrusted, s.move_cm, s.move_at, s.turn_deg,
                    s.turn_at, s.over_20);
      }
    }
    PrintLargestMoves(r.result);
    std::fflush(stdout);
  }
}

// PCK against hand-made labels (bench/hand_labels/*.json, hands/hand_labels.h)
// per video, scored by ScoreLabels: the models alone, the tracker, the fit.
void Labels() {
  const std::filesystem::path dir = std::filesystem::path(DOASIDO_SOURCE_DIR) / "bench/hand_labels";
  std::vector<std::filesystem::path> files;
  if (std::filesystem::is_directory(dir)) {
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
      if (e.path().extension() == ".json") files.push_back(e.path());
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    std::printf("no label files in %s (see hands/hand_labels.h for the format)\n", dir.c_str());
    return;
  }
  std::printf("%-22s %6s %6s %15s %15s %15s %12s %9s %17s   %s\n", "video", "frames", "hands",
              "models PCK.1/.2", "tracker PCK.1/.2", "fit PCK.1/.2", "missed m/t/f", "swaps m/t",
              "err px m/t/f", "fit, every frame trusted: PCK.1/.2 missed");
  for (const auto& file : files) {
    const HandLabels labels = ReadHandLabels(file);
    int last = 0;
    for (const auto& f : labels.frames) last = std::max(last, f.frame);
    const Run r = RunVideo(kData + "/" + labels.video, last + 1);
    const LabelScores s = ScoreLabels(labels, r.detected, r.result);
    HandsConfig trusting;
    trusting.fit.max_untrusted_run = 0;
    const LabelScores all = ScoreLabels(
        labels, r.detected, ReconstructHands(r.detected, r.result.intrinsics, trusting));
    std::printf(
        "%-22s %6d %6d %7.3f/%.3f %7.3f/%.3f %7.3f/%.3f %8d/%d/%d %7d/%d %5.1f/%.1f/%.1f   "
        "%7.3f/%.3f %d\n",
        file.stem().c_str(), s.labelled_frames, s.fit.hands, s.models.Pck01(), s.models.Pck02(),
        s.tracker.Pck01(), s.tracker.Pck02(), s.fit.Pck01(), s.fit.Pck02(), s.models.missed,
        s.tracker.missed, s.fit.missed, s.models.swaps, s.tracker.swaps, s.models.MeanErrorPx(),
        s.tracker.MeanErrorPx(), s.fit.MeanErrorPx(), all.fit.Pck01(), all.fit.Pck02(),
        all.fit.missed);
    std::fflush(stdout);
  }
}

// The start-up tax (issue 54): in this fresh process, with the graphs
// prepared before the first clip (PrepareHandModels, as a worker does) or
// not, the same clip (02_cups, 5 samples per second at analysis size, as
// the analysis pass samples) three times, each with a new landmarker (the
// analysis makes one per clip): the models' ms per sample (what
// hands.ms_per_sample records), the clip's CPU seconds with the
// landmarker's construction, and the graph pairs built so far.
void Startup(bool prepare) {
  const double c0 = CpuSeconds();
  if (prepare) filters::PrepareHandModels(g_models);
  std::printf("prepare %s: %.3f CPU s, graph pairs built %d\n", prepare ? "on" : "off",
              CpuSeconds() - c0, filters::HandModelGraphBuilds());
  VideoDecoder decoder(kData + "/videos/02_cups.mp4", DecoderOptions{.clip = "02_cups"});
  const int every = std::max(1, static_cast<int>(std::lround(decoder.geometry().fps / 5)));
  std::vector<cv::Mat> samples;
  AnalysisFrame frame;
  for (int i = 0; decoder.Next(&frame); ++i) {
    if (i % every == 0) samples.push_back(frame.bgr.clone());
  }
  for (int clip = 1; clip <= 3; ++clip) {
    const double c = CpuSeconds();
    filters::HandLandmarker landmarker(LandmarkerOptions(0));
    double ms = 0, first_ms = 0;
    for (size_t i = 0; i < samples.size(); ++i) {
      landmarker.Detect(samples[i]);
      ms += landmarker.last_ms();
      if (i == 0) first_ms = landmarker.last_ms();
    }
    std::printf("clip %d: %zu samples, %.2f ms per sample (first sample %.1f ms), %.3f CPU s, "
                "graph pairs built %d\n",
                clip, samples.size(), ms / samples.size(), first_ms, CpuSeconds() - c,
                filters::HandModelGraphBuilds());
    std::fflush(stdout);
  }
}

// The stills made from the labelled frames (hands/labelled_stills.h): per
// video and kind, and per kind over all videos, the hands found (recall),
// PCK@0.2 (a miss counts 0), PCK@0.1 and the mean 2D error of the hands
// found (pixels, and hand boxes), left/right swaps, before (the palm detector on the whole
// image, as DetectImage was; a gray image replicated to three channels as
// the CLI reads it) and after (DetectStill: the wide search); the models'
// milliseconds per still.
struct StillScores {
  PckScore before, after;
  double before_ms = 0, after_ms = 0;
  int stills = 0;
  void Add(const StillScores& o) {
    before.Add(o.before);
    after.Add(o.after);
    before_ms += o.before_ms;
    after_ms += o.after_ms;
    stills += o.stills;
  }
};

std::vector<PredictedHand> Predicted(const std::vector<filters::LandmarkedHand>& hands, int width,
                                     int height) {
  std::vector<PredictedHand> out;
  for (const auto& h : hands) {
    const HandObservation o = FromLandmarked(h, 1.0, width, height);
    out.push_back({.side = o.p_right >= 0.5 ? Side::kRight : Side::kLeft, .uv = o.uv});
  }
  return out;
}

StillScores ScoreStill(const LabelledStill& still) {
  StillScores s;
  s.stills = 1;
  cv::Mat bgr = still.image;
  if (bgr.channels() == 1) cv::cvtColor(still.image, bgr, cv::COLOR_GRAY2BGR);
  const int w = bgr.cols, h = bgr.rows;
  PalmOnlyLandmarker().Reset();
  s.before = ScoreFrame(still.labels, Predicted(PalmOnlyLandmarker().Detect(bgr), w, h));
  s.before_ms = PalmOnlyLandmarker().last_ms();
  s.after = ScoreFrame(still.labels, Predicted(Landmarker().DetectStill(still.image), w, h));
  s.after_ms = Landmarker().last_ms();
  return s;
}

void PrintStills(const std::string& name, const StillScores& s) {
  const auto row = [](const PckScore& p) {
    char text[96];
    std::snprintf(text, sizeof text, "%3d/%-3d %5.3f %5.3f %6.1f %5.3f %2d", p.hands - p.missed,
                  p.hands, p.Pck02(), p.Pck01(), p.MeanErrorPx(), p.MeanErrorBoxes(), p.swaps);
    return std::string(text);
  };
  std::printf("%-30s %4d | %s %6.1f | %s %6.1f\n", name.c_str(), s.stills, row(s.before).c_str(),
              s.stills ? s.before_ms / s.stills : 0.0, row(s.after).c_str(),
              s.stills ? s.after_ms / s.stills : 0.0);
  std::fflush(stdout);
}

// The package a labelled photo comes from: an npm package's name, else the
// folder the Debian package installed under /usr/share (or /usr/share/doc),
// and a Qt resource file's name (GCompris: one per activity).
std::string PhotoSource(const std::string& video) {
  if (video.rfind("npm:", 0) == 0) return "npm " + video.substr(4, video.find('/', 4) - 4);
  const auto rcc = video.find(".rcc:");
  const std::filesystem::path path(video.substr(0, rcc == std::string::npos ? rcc : rcc + 4));
  const std::string file = rcc == std::string::npos ? "" : " " + path.stem().string();
  bool next = false;
  for (const auto& part : path) {
    if (next && part != "doc") return part.string() + file;
    next = next || part == "share";
  }
  return path.parent_path().string() + file;
}

// The photos labelled by hand (bench/hand_labels/photos/*.json) and their
// gray versions: each, then per source and kind; `kinds` gets them per kind.
void Photos(const std::filesystem::path& dir, std::map<std::string, StillScores>* kinds) {
  std::vector<std::filesystem::path> photos;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() == ".json") photos.push_back(e.path());
  }
  std::sort(photos.begin(), photos.end());
  std::map<std::string, StillScores> sources;
  for (const auto& file : photos) {
    const std::string source = PhotoSource(ReadHandLabels(file).video);
    for (const LabelledStill& still : PhotoStills(file)) {
      const StillScores scores = ScoreStill(still);
      PrintStills(still.name + " " + still.kind, scores);
      (*kinds)[still.kind].Add(scores);
      sources[source + " " + still.kind].Add(scores);
    }
  }
  for (const auto& [source, scores] : sources) PrintStills(source, scores);
}

void Stills() {
  const std::filesystem::path dir = std::filesystem::path(DOASIDO_SOURCE_DIR) / "bench/hand_labels";
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() == ".json") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  std::printf("%-30s %4s | %-35s | %-35s\n", "source (video, kind)", "n",
              "before: found PCK.2 PCK.1 err_px err_box swaps ms", "after (wide search): same");
  std::map<std::string, StillScores> kinds;
  for (const auto& file : files) {
    const HandLabels labels = ReadHandLabels(file);
    std::map<std::string, StillScores> mine;
    for (const LabelledFrame& f : labels.frames) {
      const cv::Mat bgr = DecodeFrame(kData + "/" + labels.video, f.frame);
      for (const LabelledStill& still :
           StillsOfFrame(bgr, f, file.stem().string() + " " + std::to_string(f.frame))) {
        mine[still.kind].Add(ScoreStill(still));
      }
    }
    for (const auto& [kind, scores] : mine) {
      PrintStills(file.stem().string() + " " + kind, scores);
      kinds[kind].Add(scores);
    }
  }
  Photos(dir / "photos", &kinds);
  StillScores total;
  for (const auto& [kind, scores] : kinds) {
    PrintStills("all " + kind, scores);
    total.Add(scores);
  }
  PrintStills("all", total);
}

int main(int argc, char** argv) {
  InitLogging("warn");
  const std::string mode = argc > 1 ? argv[1] : "real";
  const long arg = argc > 2 ? std::atol(argv[2]) : 0;
  if (argc > 3) g_models = argv[3];
  if (argc > 4) g_unchanged_crop = std::atof(argv[4]);
  if (argc > 5) g_wide_every = std::atoi(argv[5]);
  if (mode == "real")
    Real(arg);
  else if (mode == "dex")
    Dex(arg);
  else if (mode == "jumps")
    Jumps(arg);
  else if (mode == "labels")
    Labels();
  else if (mode == "stills")
    Stills();
  else if (mode == "photos") {
    std::map<std::string, StillScores> kinds;
    Photos(std::filesystem::path(DOASIDO_SOURCE_DIR) / "bench/hand_labels/photos", &kinds);
    for (const auto& [kind, scores] : kinds) PrintStills("all " + kind, scores);
  }
  else if (mode == "startup")
    Startup(argc > 2 && arg != 0);
  else if (mode == "synth")
    Synth(argc > 2 ? static_cast<int>(arg) : 4);
  else {
    std::fprintf(stderr,
                 "usage: hands_bench real|dex|jumps|labels|stills|photos|startup|synth [frames|clips] "
                 "[models]\n");
    return 2;
  }
  return 0;
}
