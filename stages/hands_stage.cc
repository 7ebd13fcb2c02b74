#include "stages/hands_stage.h"

#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/error_codes.h"
#include "filters/hand_models.h"
#include "filters/kept_shot.h"
#include "filters/shot_boundary.h"
#include "hands/hand_bundle_writer.h"
#include "hands/hand_detection.h"
#include "hands/hand_reconstruction.h"
#include "stages/clip_inputs.h"

namespace doasido::stages {

using namespace hands;  // the algorithms this stage runs
namespace {

// The kept span as decoder options (see the header).
DecoderOptions KeptSpan(const ClipContext& context, const std::string& clip) {
  DecoderOptions span;
  span.clip = clip;
  const ClipRecord& c = context.clip;
  span.first_frame = c.start_frame.value_or(0);
  span.last_frame = c.end_frame.value_or(-1);
  if (!c.start_frame && c.start_s) span.first_s = *c.start_s;
  if (!c.end_frame && c.end_s) span.last_s = *c.end_s;
  const auto shot = context.measurements.find(filters::kShotBoundaryStageName);
  if (shot != context.measurements.end()) {
    const auto kept = filters::ReadKeptShot(shot->second);
    if (kept && kept->trim) {
      span.first_frame = kept->trim->start_frame;
      span.last_frame = kept->trim->end_frame;
      span.first_s = span.last_s = -1;
    }
  }
  return span;
}

void EmptyFolder(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  std::filesystem::create_directories(dir);
}

}  // namespace

HandsStage::HandsStage(HandsConfig config) : config_(std::move(config)) {
  CheckConfig(config_, kHandsStageName);
}

HandsStage::~HandsStage() = default;

void HandsStage::Prepare() {
  // A native runtime that cannot load falls back on the first clip, saying why.
  if (config_.backend == filters::kBackendNative) filters::PrepareHandModels(config_.models);
}

Intrinsics ClipIntrinsics(const ClipContext& context, int width, int height,
                          double default_fov_deg) {
  const std::string clip = ClipName(context);
  if (ListNamesBundle(context)) {
    const auto dir = BundleDir(context);
    if (std::filesystem::exists(dir / "K.npz")) {
      const recon::ClipBundle b = recon::ReadClipBundle(dir, clip);
      return {.K = ScaleK(b.KAt(0), b.width, b.height, width, height),
              .assumed = false,
              .source = kIntrinsicsFromBundle};
    }
  }
  if (auto listed = IntrinsicsFromList(context.clip.metadata, width, height, clip)) return *listed;
  return {.K = KFromFov(width, height, default_fov_deg),
          .assumed = true,
          .source = kIntrinsicsFromDefault};
}

StageResult HandsStage::Run(const ClipContext& context) {
  const std::string clip = ClipName(context);
  if (ListNamesBundle(context) && std::filesystem::exists(BundleDir(context) / "hands.npz")) {
    // The list's bundle wins and already has hands: nothing to fill in.
    StageResult skipped;
    skipped.measurements = {{"skipped", "the bundle the list names has hands"},
                            {"bundle", BundleDir(context).string()}};
    return skipped;
  }
  if (context.video.info) {
    // Refuse bad intrinsics before minutes of detection.
    ClipIntrinsics(context, context.video.info->width, context.video.info->height,
                   config_.default_fov_deg);
  }
  if (!landmarker_) {
    landmarker_ = std::make_unique<filters::HandLandmarker>(filters::HandLandmarkerOptions{
        .max_hands = config_.max_hands, .max_side = config_.max_side, .clip = clip,
        .backend = config_.backend, .models = config_.models, .palm_every = config_.palm_every,
        .lost_search = config_.palm_every, .wide_every = config_.wide_search_every,
        .lost_wide = config_.lost_wide_search});
  }
  DetectedFrames detected;
  try {
    detected = DetectVideo(context.video.path, KeptSpan(context, clip), config_.max_side, *landmarker_);
  } catch (const Error& e) {
    if (IsPermanentError(e.code())) throw;
    // A detector that failed is started afresh on the next attempt; the
    // long-lived detector names the clip it started on, so name this one.
    if (e.code() == "hand_detector_failed") landmarker_.reset();
    ErrorSite site = e.site();
    site.clip = clip;
    throw Error(e.code(), e.message(), site);
  }
  if (detected.frames.empty()) {
    throw Error(kVideoTruncated, "the kept span holds no frame",
                         {.clip = clip, .file = context.video.path});
  }
  const Intrinsics intrinsics =
      ClipIntrinsics(context, detected.width, detected.height, config_.default_fov_deg);
  const HandsResult result = ReconstructHands(detected, intrinsics, config_);
  EmptyFolder(context.artifact_dir);
  WriteHandBundle(detected, result, context.artifact_dir);

  StageResult out;
  out.measurements = Summarize(detected, result);
  out.measurements["first_frame"] = detected.first_frame;
  out.measurements["last_frame"] = detected.first_frame + static_cast<std::int64_t>(detected.frames.size()) - 1;
  out.measurements["bundle"] = context.artifact_dir.string();
  out.artifacts = {{"bundle", "meta.json"}, {"hands", "hands.npz"}, {"keypoints", kKeypointsFile}};
  if (result.tracks.empty()) {
    out.verdict = Verdict::kReject;
    out.reason = kReasonNoHands;
  }
  spdlog::info("{} {}: {} frames, {} tracks, fit {:.1f} s", kHandsStageName, clip,
               detected.frames.size(), result.tracks.size(), result.fit_seconds);
  return out;
}

}  // namespace doasido::stages
