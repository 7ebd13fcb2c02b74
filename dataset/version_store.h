// The dataset root: named datasets, each a sequence of immutable versions
// <root>/<name>/v1, v2, ... A version is built in a hidden temporary folder
// beside them and renamed into place in one step, so a reader (or a killed
// writer) never sees part of one; an existing version is never written to.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "dataset/splits.h"
#include "dataset/version.h"
#include "db/database.h"

namespace doasido::dataset {

inline constexpr const char* kDefaultDatasetName = "default";
// A run a version selected changed (queued again, finished again) while the
// version was being written: nothing is published; a retry once the
// workers are done succeeds.
inline constexpr const char* kRunsChanged = "runs_changed";

struct CreateOptions {
  std::string name = kDefaultDatasetName;  // [A-Za-z0-9_.-]+, not starting with '.'
  Selection selection = Selection::kVerified;
  SplitFractions splits = {{"train", 0.8}, {"val", 0.1}, {"test", 0.1}};
  std::int64_t seed = 0;
  bool thumbnails = true;  // in the playbook report
  bool allow_empty = false;  // else Error("empty_version") when nothing is selected
  // Else Error("unsettled_runs") naming the clips whose runs are pending,
  // running or stale (dataset/settled_runs.h); allowed, the manifest
  // records it and those clips.
  bool allow_stale = false;
};

// Every version under `root`, by name then number.
struct VersionRef {
  std::string name;
  std::string version;  // "v3"
  int number = 0;
  std::filesystem::path dir;
};
std::vector<VersionRef> ListVersions(const std::filesystem::path& root);
// Folders named vK that hold no manifest (copied by hand, or left by other
// tools): not versions, never written to; `create` numbers past them and
// names them, `list` names them.
std::vector<VersionRef> ListStrayVersions(const std::filesystem::path& root);

// Resolves "v3", "name/v3" or a folder path to a version folder holding a
// manifest; `name` is used for a bare "vK". Throws Error("no_version")
// listing the versions that exist.
std::filesystem::path FindVersion(const std::filesystem::path& root, const std::string& name,
                                  const std::string& version);

// Makes the next version of `options.name` from `db`: selects the episodes,
// assigns splits, copies each episode's trajectory, its trajectory stage's
// and its reconstruction's artifact folders, writes the playbook report of
// every clip considered and the manifest with each file's SHA-256, then
// renames the folder into place. Refuses unsettled runs (see
// CreateOptions::allow_stale) before writing anything. `progress(done, total)` is called per
// episode. Temporary folders that killed runs left behind are removed
// first. Throws Error("empty_version") when no clip is selected (unless
// allowed), Error("version_exists") when another process created the same
// version first, Error(kRunsChanged) naming the clip and stage whose run
// changed while it copied (checked again before the rename, so a version
// never holds files of runs other than those it records), Error("io")
// naming a file it cannot copy or write. Holds the artifact root's reading
// lock throughout (Database::LockForReading): a merge is never seen half
// placed.
Manifest CreateVersion(Database& db, const std::filesystem::path& root, const CreateOptions& options,
                       const std::function<void(int, int)>& progress = {});

}  // namespace doasido::dataset
