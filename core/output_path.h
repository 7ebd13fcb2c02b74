// The one check every writing command makes before it writes: an output
// path must never be one of the project's inputs. A robomimic export named
// like the database would otherwise replace the queue with an HDF5 file, an
// export into a version's folder would break its manifest, and `--out
// /dev/null` would "succeed".
//
// CheckOutputPath refuses (Error("unsafe_output"), naming the path and the
// option) an output that
//   - is a device, FIFO or socket, or lies under /dev, /proc or /sys;
//   - is a SQLite database (any file starting with SQLite's header, or a
//     database the caller names, or its -wal/-shm/-journal companion);
//   - is or lies inside a dataset version (a folder holding manifest.json);
//   - is or lies inside an artifact root (<database folder>/artifacts of a
//     database the caller names, a folder holding kArtifactRootMarker, or
//     any `artifacts` folder beside a SQLite database);
//   - is, or is a folder holding, one of the command's input files (a
//     folder output replaced whole would delete them);
//   - exists and is of another kind than the command writes (a folder for
//     a file output, a file for a folder output, or a file/folder the
//     command does not recognise as its own output);
//   - exists as the command's own earlier output while `force` is false
//     (Error("output_exists"), saying --force replaces it).
// An empty existing folder is always accepted for a folder output.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace doasido {

inline constexpr const char* kUnsafeOutput = "unsafe_output";
inline constexpr const char* kOutputExists = "output_exists";
// The file that marks a folder as a database's artifact root (the database
// writes it when it claims the folder; Database::kArtifactOwnerFile).
inline constexpr const char* kArtifactRootMarker = ".doasido-database";

struct OutputRequest {
  std::filesystem::path path;  // as given (relative to the working directory)
  enum class Kind { kFile, kFolder } kind = Kind::kFile;
  std::string option = "--out";  // named in the error
  std::string what;              // "robomimic HDF5 file", named in errors
  // Whether an existing file or non-empty folder at `path` is an earlier
  // output of the same command (only those may be replaced, with `force`).
  // Empty: nothing existing may be replaced.
  std::function<bool(const std::filesystem::path&)> is_own_output;
  bool force = false;
  // Databases (and so their artifact roots) the command works with.
  std::vector<std::filesystem::path> databases;
  // Files the command reads (a hand model, a URDF and its meshes' folder).
  std::vector<std::filesystem::path> inputs;
};

void CheckOutputPath(const OutputRequest& request);

// True when `path` is a regular file starting with SQLite's header.
bool IsSqliteFile(const std::filesystem::path& path);
// True when `path` is a regular file whose first bytes are `magic`.
bool FileStartsWith(const std::filesystem::path& path, const std::string& magic);

}  // namespace doasido
