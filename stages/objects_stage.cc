#include "stages/objects_stage.h"

#include <chrono>

#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/error_codes.h"
#include "core/file_text.h"
#include "objects/object_bundle_writer.h"
#include "ingest/object_prompt.h"
#include "objects/object_detection.h"
#include "objects/object_prompts.h"
#include "objects/object_reconstruction.h"
#include "recon/bundle/bundle_location.h"
#include "stages/clip_inputs.h"

namespace doasido::stages {

using namespace objects;  // the algorithms this stage runs
namespace {

// The hands stage's span start (file frame of its frame 0), from its
// keypoints.json; 0 when it does not say.
int HandsFirstFrame(const std::filesystem::path& hands_dir) {
  const auto text = TryReadFile(hands_dir / "keypoints.json");
  if (!text) return 0;
  const Json j = Json::parse(*text, nullptr, false);
  return j.is_object() ? j.value("first_frame", 0) : 0;
}

int Count(const ObjectTrack& t, bool ObjectFrame::*flag) {
  int n = 0;
  for (const ObjectFrame& f : t.frames) n += f.*flag;
  return n;
}

Json Measurements(const ObjectsResult& r, size_t observations) {
  Json m = {{kMeasureObservations, observations},
            {kMeasureTracks, r.tracks.size()},
            {kMeasureUnknownCategories, r.unknown_categories}};
  if (r.chosen < 0) {
    m[kMeasureObjectCategory] = "none";
    return m;
  }
  const ObjectTrack& t = r.tracks[r.chosen];
  m[kMeasureObjectCategory] = t.category;
  m[kMeasureObjectSize] = {t.size_m.x(), t.size_m.y(), t.size_m.z()};
  m[kMeasureScaleSource] = t.scale_source;
  m[kMeasureScaleAssumed] = t.scale_assumed;
  m[kMeasureContactFrames] = t.contact_frames;
  m[kMeasureContactResidual] = t.contact_residual_m;
  m[kMeasureObservedFrames] = t.ObservedFrames();
  m[kMeasureFilledFrames] = Count(t, &ObjectFrame::filled);
  m[kMeasureCarriedFrames] = Count(t, &ObjectFrame::carried);
  m[kMeasureDegenerateFrames] = Count(t, &ObjectFrame::degenerate);
  return m;
}

// The seed boxes of the clip's object prompt (its list row's object_box),
// none when it has no prompt.
std::vector<SeedBox> ClipPrompt(const ClipContext& context, const std::string& clip) {
  const Json& meta = context.clip.metadata;
  if (!meta.is_object() || !meta.contains(ingest::kObjectBoxColumn)) return {};
  const Json& cell = meta[ingest::kObjectBoxColumn];
  if (!cell.is_string()) {
    throw Error(kBadObjectBox, "not text", {.clip = clip, .field = ingest::kObjectBoxColumn});
  }
  return SeedsFromPrompt(cell.get<std::string>(), clip, ingest::kObjectBoxColumn);
}

int SeedsInSpan(const std::vector<SeedBox>& seeds, const FrameSpan& span) {
  int n = 0;
  for (const SeedBox& s : seeds) n += s.frame >= span.first_frame && s.frame < span.first_frame + span.frames;
  return n;
}

}  // namespace

ObjectsStage::ObjectsStage(ObjectsConfig config) : config_(std::move(config)) {
  CheckConfig(config_, kObjectsStageName);
}

StageResult ObjectsStage::Run(const ClipContext& context) {
  const std::string clip = ClipName(context);
  StageResult out;
  if (ListNamesBundle(context)) {
    out.measurements = {{"skipped", "the list names the clip's bundle"},
                        {"bundle", BundleDir(context).string()}};
    return out;
  }
  const std::vector<SeedBox> prompt = ClipPrompt(context, clip);  // checked before any work
  const auto hands_dir = SiblingArtifactDir(context, recon::kHandsStageFolder);
  if (!std::filesystem::is_regular_file(hands_dir / "meta.json")) {
    out.measurements = {{"skipped", "no output of the hands stage (its span, K and hands)"}};
    return out;
  }
  const auto start = std::chrono::steady_clock::now();
  const recon::ClipBundle hands = recon::ReadClipBundle(hands_dir, clip);
  const FrameSpan span{.first_frame = HandsFirstFrame(hands_dir), .frames = hands.frames};
  std::vector<ObjectObservation> observations;
  ObjectsResult result;
  try {
    const HandsByFrame near = HandsFromBundle(hands, span.first_frame);
    observations = DetectObjects(context.video.path, span, config_, &near, prompt);
    result = ReconstructObjects(observations, hands, config_);
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.clip = clip;
    throw Error(e.code(), e.message(), site);
  }
  std::error_code ec;
  std::filesystem::remove_all(context.artifact_dir, ec);
  WriteObjectBundle(result, hands, span.first_frame, context.artifact_dir, config_.cylinder_segments);
  out.measurements = Measurements(result, observations.size());
  out.measurements["first_frame"] = span.first_frame;
  if (!prompt.empty()) {
    out.measurements[kMeasurePromptBoxes] = prompt.size();
    out.measurements[kMeasurePromptBoxesInSpan] = SeedsInSpan(prompt, span);
  }
  out.measurements["seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.artifacts = {{"objects", kObjectsFile}};
  if (result.chosen < 0) {
    out.reason = kReasonNoKnownObject;
  } else {
    out.artifacts.emplace_back("bundle", "meta.json");
    out.artifacts.emplace_back("object_mesh", "object/mesh.obj");
    out.artifacts.emplace_back("object_poses", "object/poses.npz");
  }
  spdlog::info("{} {}: {} observations, {} tracks, object {}", kObjectsStageName, clip,
               observations.size(), result.tracks.size(),
               out.measurements[kMeasureObjectCategory].get<std::string>());
  return out;
}

}  // namespace doasido::stages
