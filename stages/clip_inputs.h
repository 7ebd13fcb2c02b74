// Where a clip's inputs are for the stages that read another stage's
// output (bundle, hands, track, recon, retarget_kinematic, retarget): its
// bundle, resolved from the list row, the model command's output or the
// hands stage's, and the published folders of earlier stages.
#pragma once

#include <filesystem>
#include <string>

#include "core/config.h"
#include "db/stage_records.h"
#include "recon/bundle/bundle.h"
#include "recon/bundle/bundle_location.h"

namespace doasido::stages {

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
//   - with neither, the hands stage's bundle is the clip's bundle, and the
//     objects stage's object part (<artifacts>/<clip>/objects/: mesh and
//     metric poses) is added to it when that stage found an object (same
//     frame count required);
// Errors are ReadClipBundle's (permanent, clip named); Error("no_bundle")
// (permanent) when there is no bundle at all.
struct ResolvedBundle {
  recon::ClipBundle bundle;
  std::filesystem::path dir;       // the bundle read (the hands folder for kBundleFromHands)
  std::string source;              // kBundleFromList, kBundleFromCommand or kBundleFromHands
  std::string hands_source;        // "bundle", kBundleFromHands, or "none"
  std::string object_source;       // "bundle", kObjectsStageFolder, or "none"
  Json hands_meta = Json::object();  // the hands stage's meta.json when its hands are used
};
// `model_output`, given by the bundle stage itself, is the folder its model
// command or server just wrote into (its run's own folder, not yet the
// recorded one); later stages leave it empty and get the recorded bundle.
ResolvedBundle LoadClipBundle(const ClipContext& context,
                              const std::filesystem::path& model_output = {});

}  // namespace doasido::stages
