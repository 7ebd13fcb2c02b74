#include "stages/track_stage.h"

#include <spdlog/spdlog.h>

#include <memory>

#include "core/config_check.h"
#include "core/error.h"
#include "core/error_codes.h"
#include "core/shell_words.h"
#include "recon/bundle/bundle.h"
#include "stages/clip_inputs.h"
#include "recon/track/gaussian_mixture_flow.h"
#include "recon/track/lucas_kanade_follower.h"
#include "recon/bundle/npy.h"
#include "recon/track/object_tracker.h"
#include "recon/track/silhouette.h"
#include "recon/track/velocity_server.h"

namespace doasido::stages {

using namespace recon;  // the algorithms this stage runs
namespace {

// The bundle's pose samples as a model: one mode per sample. Quaternions
// are put in the hemisphere of the previous frame's mean, so that a mode
// and the guidance toward the previous pose use the same sign.
std::unique_ptr<VelocityField> CandidatesModel(const ClipBundle& b, double sigma) {
  std::vector<Mixture> frames;
  Quat reference = b.candidates.at(0).at(0).pose.q;
  for (const auto& samples : b.candidates) {
    Mixture modes;
    Eigen::Vector4d mean = Eigen::Vector4d::Zero();
    for (const PoseSample& s : samples) {
      Pose p = s.pose;
      p.q = SameHemisphere(p.q, reference);
      mean += p.q.coeffs();
      modes.push_back({1.0, PoseBlock(p).transpose(), sigma});
    }
    if (mean.norm() > 1e-9) reference = Quat(mean.normalized());
    frames.push_back(std::move(modes));
  }
  return std::make_unique<GaussianMixtureFlow>(FlowLayout{.shape_dim = 0}, std::move(frames));
}

void WriteTrack(const std::filesystem::path& file, const std::vector<TrackedFrame>& track) {
  const auto T = static_cast<std::int64_t>(track.size());
  const auto N = static_cast<std::int64_t>(track.empty() ? 0 : track[0].candidates.size());
  std::vector<double> poses, candidates, score, alpha;
  std::vector<std::int64_t> chosen;
  for (const TrackedFrame& f : track) {
    const auto row = PoseBlock(f.pose);
    poses.insert(poses.end(), row.data(), row.data() + kPoseDim);
    for (const Pose& c : f.candidates) {
      const auto r = PoseBlock(c);
      candidates.insert(candidates.end(), r.data(), r.data() + kPoseDim);
    }
    chosen.push_back(f.choice.index);
    score.push_back(f.choice.score);
    alpha.push_back(f.pose_guidance);
  }
  WriteNpz(file, {{"poses", MakeArray({T, kPoseDim}, poses)},
                  {"candidates", MakeArray({T, N, kPoseDim}, candidates)},
                  {"chosen", MakeArray({T}, chosen)},
                  {"score", MakeArray({T}, score)},
                  {"alpha_p", MakeArray({T}, alpha)}});
}

cv::Mat Occluders(const ClipBundle& b, int k) {
  cv::Mat out;
  for (const auto* masks : {&b.mask_hand_left, &b.mask_hand_right}) {
    if (static_cast<int>(masks->size()) <= k || (*masks)[k].empty()) continue;
    out = out.empty() ? (*masks)[k].clone() : (out | (*masks)[k]);
  }
  return out;
}

// The model the tracker samples from: the configured velocity server, else
// the bundle's pose candidates; nullptr when there is neither. Says which in
// `m` (kMeasureTrackSource).
std::unique_ptr<VelocityField> ObjectModel(const TrackStageConfig& config, const ClipBundle& b,
                                           const std::filesystem::path& dir,
                                           const std::string& clip,
                                           const std::filesystem::path& artifact_dir, Json& m) {
  if (!config.server.empty()) {
    // Quoted as the bundle stage quotes its command's values: a clip id or
    // a path with spaces or shell characters stays one word.
    std::string command = config.server;
    ReplaceAll(command, "{bundle}", ShellQuote(dir.string()));
    ReplaceAll(command, "{clip}", ShellQuote(clip));
    m[kMeasureTrackSource] = "server";
    return std::make_unique<VelocityServer>(command, artifact_dir / "track.log");
  }
  if (!b.candidates.empty() && !b.candidates[0].empty()) {
    m[kMeasureTrackSource] = "candidates";
    return CandidatesModel(b, config.kde_sigma);
  }
  m[kMeasureTrackSource] = "none";
  return nullptr;
}

// alpha_p per frame: from the bundle's point tracks, else from Lucas-Kanade
// flow of the clip's video, where the object has masks; else the configured
// constant. Says which in `m` (kMeasureGuidanceSource).
std::vector<double> PoseGuidance(const TrackStageConfig& config, const ClipBundle& b,
                                 const ClipContext& context, Json& m) {
  const bool masks = static_cast<int>(b.mask_object.size()) == b.frames;
  if (b.tracks && masks) {
    m[kMeasureGuidanceSource] = "tracks";
    return EstimatePoseGuidance(b.mask_object, FollowPointTracks(*b.tracks, config.track_radius_px),
                                config.guidance).alpha_p;
  }
  if (masks && !context.video.path.empty() &&
      std::filesystem::is_regular_file(context.video.path)) {
    const auto gray = ReadGrayFrames(context.video.path, context.clip.start_frame.value_or(0),
                                     b.frames, b.width, b.height);
    m[kMeasureGuidanceSource] = "lucas_kanade";
    return EstimatePoseGuidance(b.mask_object, FollowWithLucasKanade(gray), config.guidance)
        .alpha_p;
  }
  m[kMeasureGuidanceSource] = "fixed";
  return std::vector<double>(b.frames, config.pose_guidance);
}

// Frames tracked, mean alpha_p (returned too), frames chosen among outliers
// only, and the time spent sampling and selecting.
double AddTrackMeasurements(const std::vector<TrackedFrame>& track, Json& m) {
  double alpha = 0, sampling = 0, selection = 0;
  int outliers = 0;
  for (const TrackedFrame& f : track) {
    alpha += f.pose_guidance / track.size();
    sampling += f.sampling_seconds;
    selection += f.selection_seconds;
    outliers += f.choice.outliers_only;
  }
  m[kMeasureTrackedFrames] = track.size();
  m[kMeasureMeanPoseGuidance] = alpha;
  m[kMeasureOutlierFrames] = outliers;
  m[kMeasureSamplingSeconds] = sampling;
  m[kMeasureSelectionSeconds] = selection;
  return alpha;
}

}  // namespace

void CheckConfig(const TrackStageConfig& c, const std::string& section) {
  RequireInRange(section, "kde_sigma", c.kde_sigma, 1e-6, 10);
  RequireInRange(section, "pose_guidance", c.pose_guidance, 0, 1);
  RequireInRange(section, "track_radius_px", c.track_radius_px, 0.1, 1000);
  CheckConfig(c.flow, section + ".flow");
  CheckConfig(c.guidance, section + ".guidance");
  CheckConfig(c.selection, section + ".selection");
}

TrackStage::TrackStage(TrackStageConfig config) : config_(std::move(config)) {
  CheckConfig(config_, kTrackStageName);
}

StageResult TrackStage::Run(const ClipContext& context) {
  const std::string clip = ClipName(context);
  const ResolvedBundle resolved = LoadClipBundle(context);
  const ClipBundle& b = resolved.bundle;
  const std::filesystem::path& dir = resolved.dir;
  StageResult result;
  result.measurements["bundle"] = dir.string();
  if (!b.object_mesh && b.candidates.empty() && b.object_poses.empty() && b.mask_object.empty()) {
    // A hand-only bundle: nothing to track; recon reconstructs the hands.
    result.measurements[kMeasureTrackSource] = kTrackSourceNoObject;
    spdlog::info("{} {}: no object in the bundle; passed without tracking", kTrackStageName, clip);
    return result;
  }
  std::filesystem::create_directories(context.artifact_dir);
  std::unique_ptr<VelocityField> model =
      ObjectModel(config_, b, dir, clip, context.artifact_dir, result.measurements);
  if (!model) {
    spdlog::info("{} {}: no object model (set track.server, or give the bundle "
                 "object/candidates.npz); recon uses the bundle's poses", kTrackStageName, clip);
    return result;
  }

  TrackInputs inputs;
  const bool masks = static_cast<int>(b.mask_object.size()) == b.frames;
  inputs.pose_guidance = PoseGuidance(config_, b, context, result.measurements);
  std::unique_ptr<SilhouetteRenderer> renderer;
  if (config_.selection.method == kSelectClustering) {
    if (!b.object_mesh || !masks || b.K.empty()) {
      throw Error(kBadBundle,
                           "clustering selection needs object/mesh, K and masks/object",
                           {.clip = clip, .file = dir.string()});
    }
    renderer = std::make_unique<SilhouetteRenderer>(*b.object_mesh);
    inputs.silhouette_iou = [&](int k, const Pose& pose) {
      return renderer->IoU(pose, Camera::FromK(b.KAt(k), b.width, b.height), b.mask_object[k],
                           config_.selection.silhouette_stride, Occluders(b, k));
    };
  }
  const auto track = TrackObject(*model, b.frames, inputs, config_.flow, config_.selection);
  WriteTrack(context.artifact_dir / kTrackPosesFile, track);
  result.artifacts.emplace_back("object_poses", kTrackPosesFile);

  const double alpha = AddTrackMeasurements(track, result.measurements);
  spdlog::info("{} {}: {} frames from {} ({} guidance, mean alpha_p {:.2f}), {} selection",
               kTrackStageName, clip, track.size(),
               result.measurements[kMeasureTrackSource].get<std::string>(),
               result.measurements[kMeasureGuidanceSource].get<std::string>(), alpha,
               config_.selection.method);
  return result;
}

}  // namespace doasido::stages
