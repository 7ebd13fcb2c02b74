// The names of where a clip's bundle comes from, shared by the stages that
// read bundles (stages/clip_inputs.h finds a clip's bundle from its queue
// context) and the hands library below them.
#pragma once

#include <filesystem>
#include <string>

#include "core/error_codes.h"
#include "recon/bundle/bundle.h"

namespace doasido::recon {

// The `bundle` stage's name: its queue name, config section and artifact folder.
inline constexpr const char* kBundleStageName = "bundle";

// The `hands` stage's name and artifact folder, <artifacts>/<clip>/hands/: a
// hand-only clip bundle (meta.json, K.npz, hands.npz) measured on the video
// itself (stages/hands_stage.h, which takes its name from here: the bundle
// readers below the hands library must know it).
inline constexpr const char* kHandsStageFolder = "hands";

// The `objects` stage's name and artifact folder, <artifacts>/<clip>/objects/:
// the object part of a clip bundle (meta.json, K.npz, object/mesh.obj,
// object/poses.npz) lifted from the category models' box keypoints
// (stages/objects_stage.h; objects/objects_config.h takes its name from here).
inline constexpr const char* kObjectsStageFolder = "objects";

// No bundle named, none written by a command and no hands found (permanent).
inline constexpr const char* kErrorNoBundle = kNoBundle;

// Where a clip's bundle came from (the bundle stage's "source" measurement).
inline constexpr const char* kBundleFromList = "list";
inline constexpr const char* kBundleFromCommand = "command";
inline constexpr const char* kBundleFromHands = "hands";

// ReadBundle (recon/bundle/bundle.h) with `clip` named in its errors, which are
// permanent: the same files fail again on a retry.
ClipBundle ReadClipBundle(const std::filesystem::path& dir, const std::string& clip);

}  // namespace doasido::recon
