#include "dataset/version_files.h"

#include <algorithm>
#include <fstream>
#include <map>

#include "core/error.h"
#include "ingest/file_sha256.h"

namespace doasido::dataset {
namespace {

namespace fs = std::filesystem;

// Regular files under `dir` but the manifest: relative path -> size.
std::map<std::string, std::int64_t> ListFiles(const fs::path& dir) {
  std::map<std::string, std::int64_t> out;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    if (!it->is_regular_file()) continue;
    const std::string rel = fs::relative(it->path(), dir).generic_string();
    if (rel == kManifestFile || rel == kManifestHashFile) continue;
    out[rel] = static_cast<std::int64_t>(it->file_size());
  }
  if (ec) throw Error("io", "cannot list the version: " + ec.message(), {.file = dir.string()});
  return out;
}

}  // namespace

std::vector<FileEntry> HashFiles(const fs::path& dir) {
  std::vector<FileEntry> out;
  for (const auto& [rel, size] : ListFiles(dir)) {
    out.push_back({rel, ingest::FileSha256(dir / rel), size});
  }
  return out;
}

void WriteManifest(const Manifest& m, const fs::path& dir) {
  const fs::path path = dir / kManifestFile;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << ToJson(m).dump(1) << "\n";
  out.close();
  if (!out) throw Error("io", "cannot write the manifest", {.file = path.string()});
  const fs::path hash = dir / kManifestHashFile;
  std::ofstream h(hash, std::ios::binary | std::ios::trunc);
  h << ingest::FileSha256(path) << "  " << kManifestFile << "\n";
  h.close();
  if (!h) throw Error("io", "cannot write the manifest's hash", {.file = hash.string()});
}

std::string ManifestHashProblem(const fs::path& version_dir) {
  std::ifstream in(version_dir / kManifestHashFile);
  std::string recorded;
  if (!(in >> recorded)) {
    return std::string(kManifestHashFile) + " is missing: nothing proves the manifest unedited";
  }
  std::error_code ec;
  if (!fs::exists(version_dir / kManifestFile, ec)) return std::string(kManifestFile) + " is missing";
  if (ingest::FileSha256(version_dir / kManifestFile) != recorded) {
    return std::string(kManifestFile) + "'s SHA-256 differs from " + kManifestHashFile +
           ": the manifest was edited";
  }
  return "";
}

std::vector<FileProblem> VerifyVersion(const fs::path& version_dir) {
  std::vector<FileProblem> problems;
  if (const std::string why = ManifestHashProblem(version_dir); !why.empty()) {
    problems.push_back({kManifestFile, why});
  }
  const Manifest m = ReadManifest(version_dir);
  std::map<std::string, std::int64_t> present = ListFiles(version_dir);
  for (const FileEntry& f : m.files) {
    const auto it = present.find(f.path);
    if (it == present.end()) {
      problems.push_back({f.path, "missing"});
      continue;
    }
    if (it->second != f.size) {
      problems.push_back({f.path, "size " + std::to_string(it->second) + " bytes, manifest says " +
                                      std::to_string(f.size)});
    } else if (ingest::FileSha256(version_dir / f.path) != f.sha256) {
      problems.push_back({f.path, "SHA-256 differs from the manifest's"});
    }
    present.erase(it);
  }
  for (const auto& [rel, size] : present) problems.push_back({rel, "not in the manifest"});
  return problems;
}

}  // namespace doasido::dataset
