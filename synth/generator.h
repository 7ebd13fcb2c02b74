// The synthetic dataset generator: plans clips from a seed and a defect mix,
// renders them and writes
//   <out>/videos/<clip>.mp4          H.264 (avc1) or MPEG-4 (mp4v) via OpenCV/FFmpeg
//   <out>/bundles/<clip>/            exact ground truth in the clip bundle layout
//   <out>/Annotations/*.xml          100DOH-style VOC boxes and contact states per frame
//   <out>/gt/<clip>.json             defects with their frames, per-frame camera,
//                                    homographies, contact and in-frame facts
//   <out>/clips.csv                  video,id,start_frame,end_frame,source,defects,...
//   <out>/summary.json               the defect mix asked for and produced
//   <out>/png/<clip>_<frame>.png     optional previews (png_every > 0)
//   <out>/model_bundles/<clip>/      optional model-like bundles (model_bundles)
// Output depends only on the configuration: every random draw comes from a
// std::mt19937_64 seeded from `seed` and the clip index.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "recon/bundle/bundle.h"
#include "synth/defects.h"
#include "synth/episode.h"
#include "synth/model_noise.h"
#include "synth/objects.h"
#include "synth/voc_writer.h"

namespace doasido::synth {

struct SynthConfig {
  std::uint64_t seed = 1;
  int clips = 10;
  int width = 640;
  int height = 480;
  double fps = 30;
  int frames = 90;
  std::string mix = "clean=0.4,cut=0.1,fade=0.1,pan=0.1,out_of_frame=0.1,no_contact=0.1,static=0.1";
  std::string genre = "synth";
  std::string mesh_dir;       // optional folder of .obj/.ply/.glb objects to draw from
  double sensor_noise = 2.0;  // 8-bit levels
  double two_hand_fraction = 0.3;
  // "none", or a two-hand task every clip performs ("handover", "carry",
  // "hold_and_act"; episode.h TwoHandTask).
  std::string two_hand_task = "none";
  // How the active hand holds the object: "wrap" or "pinch" (episode.h
  // GraspType; a pinch opposes the thumb to two fingers, so a robot hand
  // retargeted from it can lift the object).
  std::string grasp = "wrap";
  int track_points = 64;
  bool write_bundles = true;
  bool write_annotations = true;
  int png_every = 0;  // > 0: also write every n-th frame to <out>/png/<clip>_<t>.png
  // Also write <out>/model_bundles/<clip>/: the bundle as foundation models
  // would hand it in (MoGe-like depth, HaWoR-like hands; see model_noise.h).
  bool model_bundles = false;
  bool point_maps = false;     // also fill ClipBundle::points (camera-frame XYZ per pixel)
  CandidateConfig candidates;
  DepthNoiseConfig depth_noise;
  HandNoiseConfig hand_noise;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(SynthConfig, seed, clips, width, height, fps,
                                                frames, mix, genre, mesh_dir, sensor_noise,
                                                two_hand_fraction, two_hand_task, grasp, track_points, write_bundles,
                                                write_annotations, png_every, model_bundles,
                                                candidates, depth_noise, hand_noise)

// Parses "clean=0.4,cut=0.1,...": weights >= 0, normalised to sum 1. Throws
// Error("bad_config", field "mix").
std::map<DefectKind, double> ParseMix(const std::string& spec);

// Defect kind of every clip: counts by largest remainder (every kind with a
// positive weight appears at least once when clips >= number of kinds), in a
// seeded random order.
std::vector<DefectKind> AssignDefects(const std::map<DefectKind, double>& mix, int clips,
                                      std::uint64_t seed);

// One rendered clip in memory.
struct RenderedClip {
  std::string id;            // also the video file stem
  std::vector<cv::Mat> bgr;  // frames as written to the video
  recon::ClipBundle bundle;  // exact ground truth (candidates from the SAM 3D-like model)
  std::vector<VocFrame> voc;
  std::vector<DefectRecord> defects;
  Json gt;  // the per-clip ground-truth JSON
};

// Plans and renders clip `index` with the given defect kind.
RenderedClip RenderClip(const SynthConfig& cfg, int index, DefectKind kind);

// The clip's bundle as models would deliver it: depth and hands corrupted by
// the MoGe-like and HaWoR-like models (seeded from cfg.seed and the clip
// index); `producers` says so.
recon::ClipBundle ModelLikeBundle(const SynthConfig& cfg, int index,
                                  const recon::ClipBundle& truth);

// Writes an mp4 through OpenCV's FFmpeg backend (avc1, falling back to
// mp4v). Throws Error("io") naming the file.
void WriteVideo(const std::vector<cv::Mat>& frames, double fps, const std::filesystem::path& path);

struct DatasetSummary {
  int clips = 0;
  std::map<std::string, int> defect_counts;  // clips per defect kind
  Json ToJson() const;
};

// Generates the whole dataset into `out` (created). `progress` is called
// after each clip with the number done.
DatasetSummary GenerateDataset(const SynthConfig& cfg, const std::filesystem::path& out,
                               const std::function<void(int)>& progress = {});

}  // namespace doasido::synth
