#include "stages/recon_stage.h"

#include <cmath>

#include <spdlog/spdlog.h>

#include "core/config_check.h"
#include "core/error.h"
#include "core/error_codes.h"
#include "stages/clip_inputs.h"
#include "recon/bundle/npy.h"

namespace doasido::recon {

void CheckConfig(const ReconStageConfig& c, const std::string& section) {
  CheckConfig(c.alignment, section + ".alignment");
  CheckConfig(c.gravity, section + ".gravity");
  RequireInRange(section, "min_aligned_fraction", c.min_aligned_fraction, 0, 1);
  RequireInRange(section, "min_aligned_frames", c.min_aligned_frames, 0, 1e9);
  RequireInRange(section, "max_scale_spread", c.max_scale_spread, 0, 10);
  RequireInRange(section, "rest_speed", c.rest_speed, 0, 1);
}

}  // namespace doasido::recon

namespace doasido::stages {

using namespace recon;  // the algorithms this stage runs

void ReadTrackPoses(const std::filesystem::path& file, int frames, std::vector<Pose>& poses,
                    std::vector<bool>& valid) {
  const std::string name = file.string();
  try {
    const NpzArchive npz = ReadNpz(file);
    const NpyArray& a = RequireKey(npz, "poses", name);
    CheckFloat(a, name, "poses");
    CheckShape(a, {frames, 7}, name, "poses");
    const std::vector<double> v = a.AsDoubleVector();
    poses.assign(frames, Pose::Identity());
    valid.assign(frames, false);
    for (int t = 0; t < frames; ++t) {
      const double* p = v.data() + 7 * t;
      Pose pose{Quat(p[3], p[4], p[5], p[6]), Vec3(p[0], p[1], p[2])};
      if (!pose.t.allFinite() || !pose.q.coeffs().allFinite()) continue;
      if (std::abs(pose.q.norm() - 1) > 1e-3) {
        throw Error(kBadTrack, "quaternion not unit in frame " + std::to_string(t),
                    {.file = name, .field = "poses"});
      }
      poses[t] = pose;
      valid[t] = true;
    }
  } catch (const Error& e) {
    if (e.code() == kBadTrack) throw;
    throw Error(kBadTrack, e.message(), {.file = name, .field = e.site().field});
  }
}

ReconStage::ReconStage(ReconStageConfig config) : config_(std::move(config)) {
  CheckConfig(config_, kReconStageName);
}

StageResult ReconStage::Run(const ClipContext& context) {
  const std::string clip = ClipName(context);
  const ResolvedBundle resolved = LoadClipBundle(context);
  const ClipBundle& bundle = resolved.bundle;
  const std::filesystem::path& dir = resolved.dir;
  if (IsHandOnly(bundle)) return RunHandOnly(context, resolved);
  std::vector<Pose> poses;
  std::vector<bool> valid;
  std::string pose_source = "bundle";
  try {
    const auto track = SiblingArtifactDir(context, kTrackStageName) / kTrackPosesFile;
    if (std::filesystem::is_regular_file(track)) {
      ReadTrackPoses(track, bundle.frames, poses, valid);
      pose_source = "track";
    } else {
      poses = bundle.object_poses;
      valid.assign(poses.size(), true);
    }
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.clip = clip;
    throw Error(e.code(), e.message(), site);  // kBadTrack: the same files fail again
  }
  StageResult result;
  result.measurements["bundle"] = dir.string();
  result.measurements[kMeasurePoseSource] = pose_source;
  // Metric poses (the objects stage's) need no object mask: no alignment.
  if (!bundle.object_mesh || poses.empty() ||
      (bundle.mask_object.empty() && !ObjectPosesAreMetric(bundle))) {
    result.verdict = Verdict::kReject;
    result.reason = kReasonNoObject;
    return result;
  }
  ReconOutput out = Reconstruct(bundle, poses, valid, config_);
  std::filesystem::create_directories(context.artifact_dir);
  SaveObj(*bundle.object_mesh, context.artifact_dir / kReconstructionMesh);
  out.reconstruction.object_mesh = context.artifact_dir / kReconstructionMesh;
  out.reconstruction.info["bundle"] = dir.string();
  out.reconstruction.info["object_pose_source"] = pose_source;
  WriteReconstruction(out.reconstruction, context.artifact_dir);
  result.artifacts.emplace_back("reconstruction", kReconstructionNpz);
  result.artifacts.emplace_back("reconstruction_info", kReconstructionJson);
  result.artifacts.emplace_back("object_mesh", kReconstructionMesh);
  out.measurements.update(result.measurements);
  result.measurements = out.measurements;
  if (auto decided = Redecide(result.measurements)) {
    result.verdict = decided->verdict;
    result.reason = decided->reason;
  }
  spdlog::info("{} {}: {}/{} frames aligned, scale {}, gravity {}", kReconStageName, clip,
               out.alignment.aligned_frames, bundle.frames,
               result.measurements[kMeasureScaleMedian].dump(), out.gravity.source);
  return result;
}

StageResult ReconStage::RunHandOnly(const ClipContext& context, const ResolvedBundle& resolved) const {
  ReconOutput out = ReconstructHandOnly(resolved.bundle, config_);
  StageResult result;
  result.measurements = out.measurements;
  result.measurements["bundle"] = resolved.dir.string();
  result.measurements[kMeasureBundleSource] = resolved.source;
  if (resolved.hands_meta.contains(kMeasureIntrinsicsAssumed)) {
    result.measurements[kMeasureIntrinsicsAssumed] = resolved.hands_meta[kMeasureIntrinsicsAssumed];
  }
  if (result.measurements[kMeasureRightFrames] == 0 && result.measurements[kMeasureLeftFrames] == 0) {
    result.verdict = Verdict::kReject;
    result.reason = kReasonNoHands;
    return result;
  }
  out.reconstruction.info["bundle"] = resolved.dir.string();
  out.reconstruction.info["bundle_source"] = resolved.source;
  out.reconstruction.info[kMeasureIntrinsicsAssumed] =
      result.measurements.value(kMeasureIntrinsicsAssumed, Json(nullptr));
  std::filesystem::create_directories(context.artifact_dir);
  std::filesystem::remove(context.artifact_dir / kReconstructionMesh);  // an earlier run's object
  WriteReconstruction(out.reconstruction, context.artifact_dir);
  result.artifacts.emplace_back("reconstruction", kReconstructionNpz);
  result.artifacts.emplace_back("reconstruction_info", kReconstructionJson);
  spdlog::info("{} {}: hand-only, {} right / {} left frames, gravity {}{}", kReconStageName,
               ClipName(context), result.measurements[kMeasureRightFrames].get<int>(),
               result.measurements[kMeasureLeftFrames].get<int>(), out.gravity.source,
               result.measurements[kMeasureGravityAssumed].get<bool>() ? " (assumed)" : "");
  return result;
}

std::optional<StageResult> ReconStage::Redecide(const Json& m) const {
  if (!m.contains(kMeasureAlignedFrames) || !m.contains(kMeasureEvidenceShare)) return std::nullopt;
  StageResult r;
  r.measurements = m;
  const int aligned = m[kMeasureAlignedFrames].get<int>();
  if (aligned < config_.min_aligned_frames ||
      m[kMeasureEvidenceShare].get<double>() < config_.min_aligned_fraction) {
    r.verdict = Verdict::kReject;
    r.reason = kReasonTooFewAlignedFrames;
  } else if (m[kMeasureScaleSpread].is_number() &&
             m[kMeasureScaleSpread].get<double>() > config_.max_scale_spread) {
    r.verdict = Verdict::kFlag;
    r.reason = kReasonScaleInconsistent;
  }
  return r;
}

}  // namespace doasido::stages
