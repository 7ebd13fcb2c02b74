#include "stages/clip_inputs.h"

#include "core/file_text.h"
#include "core/error.h"
#include "core/error_codes.h"

namespace doasido::stages {

using namespace recon;  // the algorithms this stage runs

bool ListNamesBundle(const ClipContext& context) {
  const Json& meta = context.clip.metadata;
  return meta.is_object() && meta.contains("bundle") && meta["bundle"].is_string() &&
         !meta["bundle"].get<std::string>().empty();
}

std::filesystem::path BundleDir(const ClipContext& context) {
  if (ListNamesBundle(context)) {
    std::filesystem::path p = context.clip.metadata["bundle"].get<std::string>();
    if (p.is_relative() && !context.clip.source_list.empty()) {
      p = std::filesystem::path(context.clip.source_list).parent_path() / p;
    }
    return p;
  }
  return SiblingArtifactDir(context, kBundleStageName);
}

std::filesystem::path SiblingArtifactDir(const ClipContext& context, const std::string& stage) {
  // The output of the run the database records (ClipContext::inputs); a
  // context made by hand (tests, tools) has no inputs: the sibling folder.
  if (const auto it = context.inputs.find(stage); it != context.inputs.end()) return it->second;
  return context.artifact_dir.parent_path() / stage;
}

std::string ClipName(const ClipContext& context) {
  return context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                          : context.clip.external_id;
}

namespace {

bool HasHands(const ClipBundle& b) { return b.hand_left.has_value() || b.hand_right.has_value(); }

// The hands stage's meta.json as JSON (its extra keys, e.g.
// intrinsics_assumed, are not part of ClipBundle).
Json HandsMeta(const std::filesystem::path& dir) {
  try {
    const Json j = Json::parse(ReadFileOrThrow(dir / "meta.json", "io", "cannot read"));
    return j.is_object() ? j : Json::object();
  } catch (const std::exception&) {
    return Json::object();  // ReadBundle has already judged the file
  }
}

bool HasObject(const ClipBundle& b) { return b.object_mesh.has_value() || !b.object_poses.empty(); }

// The objects stage's object part added to the hands stage's bundle, when
// that stage wrote one.
void AddObjectsStageObject(const ClipContext& context, const std::string& clip, ResolvedBundle& out) {
  const std::filesystem::path dir = SiblingArtifactDir(context, kObjectsStageFolder);
  if (!std::filesystem::is_regular_file(dir / "meta.json")) return;
  const ClipBundle objects = ReadClipBundle(dir, clip);
  if (!HasObject(objects)) return;
  if (objects.frames != out.bundle.frames) {
    throw Error(kBadBundle,
                "the objects stage has " + std::to_string(objects.frames) + " frames, the hands " +
                    std::to_string(out.bundle.frames) + "; they must cover the same span",
                {.clip = clip, .file = (dir / "meta.json").string(), .field = "frames"});
  }
  out.bundle.object_mesh = objects.object_mesh;
  out.bundle.object_poses = objects.object_poses;
  for (const char* part : {"object_mesh", "object_poses"}) {
    if (objects.present.count(part)) out.bundle.present.insert(part);
  }
  for (const auto& [key, value] : objects.producers.items()) {
    if (key != "K") out.bundle.producers[key] = value;
  }
  out.object_source = kObjectsStageFolder;
}

}  // namespace

ResolvedBundle LoadClipBundle(const ClipContext& context, const std::filesystem::path& model_output) {
  const std::string clip = ClipName(context);
  const std::filesystem::path hands_dir = SiblingArtifactDir(context, kHandsStageFolder);
  const bool hands_found = std::filesystem::is_regular_file(hands_dir / "meta.json");
  ResolvedBundle out;
  out.dir = model_output.empty() ? BundleDir(context) : model_output;
  if (ListNamesBundle(context)) {
    out.source = kBundleFromList;
  } else if (std::filesystem::is_regular_file(out.dir / "meta.json")) {
    out.source = kBundleFromCommand;
  } else if (hands_found) {
    out.dir = hands_dir;
    out.source = kBundleFromHands;
  } else {
    throw Error(kErrorNoBundle,
                         "the list names no bundle, no model command wrote one and the " +
                             std::string(kHandsStageFolder) + " stage found no hands",
                         {.clip = clip, .file = out.dir.string()});
  }
  out.bundle = ReadClipBundle(out.dir, clip);
  if (out.source == kBundleFromHands) {
    out.hands_source = HasHands(out.bundle) ? kBundleFromHands : "none";
    out.hands_meta = HandsMeta(hands_dir);
    out.object_source = "none";
    AddObjectsStageObject(context, clip, out);
    return out;
  }
  out.object_source = HasObject(out.bundle) ? "bundle" : "none";
  out.hands_source = HasHands(out.bundle) ? "bundle" : "none";
  if (HasHands(out.bundle) || !hands_found) return out;
  const ClipBundle hands = ReadClipBundle(hands_dir, clip);
  if (hands.frames != out.bundle.frames) {
    throw Error(kBadBundle,
                         "the hands stage has " + std::to_string(hands.frames) +
                             " frames, the bundle " + std::to_string(out.bundle.frames) +
                             "; they must cover the same span",
                         {.clip = clip, .file = (hands_dir / "hands.npz").string(), .field = "frames"});
  }
  out.bundle.hand_left = hands.hand_left;
  out.bundle.hand_right = hands.hand_right;
  for (const char* part : {"hand_left", "hand_right"}) {
    if (hands.present.count(part)) out.bundle.present.insert(part);
  }
  if (out.bundle.K.empty()) out.bundle.K = hands.K;
  out.bundle.producers["hands"] = hands.producers;
  out.hands_source = HasHands(out.bundle) ? kBundleFromHands : "none";
  out.hands_meta = HandsMeta(hands_dir);
  return out;
}

}  // namespace doasido::stages
