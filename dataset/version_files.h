// The files of a version folder: hashing them into the manifest, writing
// the manifest, and checking a version against it (`dataset verify`).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "dataset/version.h"

namespace doasido::dataset {

// Every regular file under `dir` except manifest.json, with its SHA-256 and
// size, sorted by path ('/'-separated, relative to `dir`). Throws
// Error("io") naming a file it cannot read.
std::vector<FileEntry> HashFiles(const std::filesystem::path& dir);

// Writes <dir>/manifest.json and its hash file (kManifestHashFile). Throws
// Error("io") naming the file.
void WriteManifest(const Manifest& m, const std::filesystem::path& dir);

// Why the manifest does not prove itself (its hash file is missing, or the
// manifest's SHA-256 differs from the one recorded), or "" when it does.
std::string ManifestHashProblem(const std::filesystem::path& version_dir);

struct FileProblem {
  std::string path;  // relative to the version folder
  std::string what;  // "missing", "size 10 != 12", "sha256 differs", "not in the manifest"
};

// Checks the manifest against its hash file, every file the manifest lists
// (presence, size, SHA-256) and that no other file was added. Empty when the version is intact. Throws what
// ReadManifest throws for a missing or malformed manifest.
std::vector<FileProblem> VerifyVersion(const std::filesystem::path& version_dir);

}  // namespace doasido::dataset
