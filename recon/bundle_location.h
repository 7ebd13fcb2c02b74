// Where a clip's bundle and reconstruction are, for every stage that reads
// them (bundle, recon, retarget_kinematic, ...).
#pragma once

#include <filesystem>
#include <string>

#include "db/stage.h"
#include "recon/bundle.h"

namespace doasido::recon {

// The `bundle` stage's name: its queue name, config section and artifact folder.
inline constexpr const char* kBundleStageName = "bundle";

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

// ReadBundle (recon/bundle.h) with `clip` named in its errors, which are
// permanent: the same files fail again on a retry.
ClipBundle ReadClipBundle(const std::filesystem::path& dir, const std::string& clip);

}  // namespace doasido::recon
