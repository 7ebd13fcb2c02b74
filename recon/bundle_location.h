// Where a clip's bundle and reconstruction are, for every stage that reads
// them (bundle, recon, retarget_kinematic, ...).
#pragma once

#include <filesystem>
#include <string>

#include "core/error_codes.h"
#include "db/stage.h"
#include "recon/bundle.h"

namespace doasido::recon {

// The `bundle` stage's name: its queue name, config section and artifact folder.
inline constexpr const char* kBundleStageName = "bundle";

// The `hands` stage's name and artifact folder, <artifacts>/<clip>/hands/: a
// hand-only clip bundle (meta.json, K.npz, hands.npz) measured on the video
// itself (hands/hands_stage.h, which takes its name from here: the bundle
// readers below the hands library must know it).
inline constexpr const char* kHandsStageFolder = "hands";

// No bundle named, none written by a command and no hands found (permanent).
inline constexpr const char* kErrorNoBundle = kNoBundle;

// Where a clip's bundle came from (the bundle stage's "source" measurement).
inline constexpr const char* kBundleFromList = "list";
inline constexpr const char* kBundleFromCommand = "command";
inline constexpr const char* kBundleFromHands = "hands";

// The clip metadata's "bundle" entry when present (absolute, or relative to
// the folder of the list the clip was ingested from), else
// <artifacts>/<clip>/bundle/ (the `bundle` stage's artifact folder, beside
// `context.artifact_dir`).
std::filesystem::path BundleDir(const ClipContext& context);

// Whether the clip's list row names a bundle folder.
bool ListNamesBundle(const ClipContext& context);

// The published folder of another stage of the same clip: the one of its
// recorded run (ClipContext::inputs) when the context was loaded from the
// database, else <artifacts>/<clip>/<stage>/ beside `context.artifact_dir`.
std::filesystem::path SiblingArtifactDir(const ClipContext& context, const std::string& stage);

// The clip's external id, else its numeric id: the name errors use.
std::string ClipName(const ClipContext& context);

// The clip's bundle as every stage after `bundle` sees it:
//   - the bundle the list names, else the one the model command wrote into
//     the bundle stage's folder (when it holds a meta.json);
//   - where that bundle has no hand (neither hand_left nor hand_right), the
//     hands stage's hands fill them in (same frame count required; the
//     hands stage's K is used when the bundle has none);
//   - with neither, the hands stage's bundle is the clip's bundle.
// Errors are ReadClipBundle's (permanent, clip named); Error("no_bundle")
// (permanent) when there is no bundle at all.
struct ResolvedBundle {
  ClipBundle bundle;
  std::filesystem::path dir;       // the bundle read (the hands folder for kBundleFromHands)
  std::string source;              // kBundleFromList, kBundleFromCommand or kBundleFromHands
  std::string hands_source;        // "bundle", kBundleFromHands, or "none"
  Json hands_meta = Json::object();  // the hands stage's meta.json when its hands are used
};
// `model_output`, given by the bundle stage itself, is the folder its model
// command or server just wrote into (its run's own folder, not yet the
// recorded one); later stages leave it empty and get the recorded bundle.
ResolvedBundle LoadClipBundle(const ClipContext& context,
                              const std::filesystem::path& model_output = {});

// ReadBundle (recon/bundle.h) with `clip` named in its errors, which are
// permanent: the same files fail again on a retry.
ClipBundle ReadClipBundle(const std::filesystem::path& dir, const std::string& clip);

}  // namespace doasido::recon
