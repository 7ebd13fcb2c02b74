#include "core/output_path.h"

#include <cstring>
#include <fstream>
#include <iterator>

#include "core/error.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;

constexpr const char* kManifestName = "manifest.json";  // dataset/version.h kManifestFile
constexpr const char* kArtifactsName = "artifacts";     // Database::ArtifactDir
constexpr char kSqliteHeader[] = "SQLite format 3";

[[noreturn]] void Refuse(const OutputRequest& r, const fs::path& resolved, const std::string& why,
                         const char* code = kUnsafeOutput) {
  std::string text = "refusing to write " + (r.what.empty() ? std::string("the output") : r.what) +
                     " to " + r.path.string();
  if (resolved != r.path) text += " (" + resolved.string() + ")";
  throw Error(code, text + ": " + why, {.file = r.path.string(), .field = r.option});
}

bool IsInside(const fs::path& path, const fs::path& folder) {
  auto p = path.begin();
  for (auto f = folder.begin(); f != folder.end(); ++f, ++p) {
    if (p == path.end() || *p != *f) return false;
  }
  return true;
}

fs::path Canonical(const fs::path& p) {
  std::error_code ec;
  fs::path out = fs::weakly_canonical(fs::absolute(p), ec);
  return ec ? fs::absolute(p).lexically_normal() : out;
}

// A folder holding a doasido dataset manifest (not any manifest.json).
bool IsVersionFolder(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_regular_file(dir / kManifestName, ec)) return false;
  std::ifstream f(dir / kManifestName, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  return text.find("doasido-dataset") != std::string::npos;
}

bool HasSqliteBeside(const fs::path& folder) {
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_regular_file(ec) && IsSqliteFile(it->path())) return true;
  }
  return false;
}

// Why `resolved` lies in a version or an artifact root, or "".
std::string InsideProtected(const fs::path& resolved, const OutputRequest& r) {
  for (const auto& db : r.databases) {
    const fs::path root = Canonical(db).parent_path() / kArtifactsName;
    if (IsInside(resolved, root)) return "it lies inside the artifact root " + root.string();
  }
  std::error_code ec;
  for (fs::path dir = resolved; !dir.empty(); dir = dir.parent_path()) {
    if (IsVersionFolder(dir)) {
      return "it lies inside the dataset version " + dir.string() + " (versions never change)";
    }
    if (fs::exists(dir / kArtifactRootMarker, ec) ||
        (dir.filename() == kArtifactsName && HasSqliteBeside(dir.parent_path()))) {
      return "it lies inside the artifact root " + dir.string();
    }
    if (dir == dir.parent_path()) break;
  }
  return "";
}

bool IsEmptyFolder(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec) && fs::is_empty(p, ec);
}

}  // namespace

bool FileStartsWith(const fs::path& path, const std::string& magic) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return false;
  std::ifstream f(path, std::ios::binary);
  std::string head(magic.size(), '\0');
  f.read(head.data(), static_cast<std::streamsize>(head.size()));
  return f.gcount() == static_cast<std::streamsize>(magic.size()) && head == magic;
}

bool IsSqliteFile(const fs::path& path) { return FileStartsWith(path, kSqliteHeader); }

void CheckOutputPath(const OutputRequest& r) {
  if (r.path.empty()) Refuse(r, r.path, "the path is empty");
  const fs::path resolved = Canonical(r.path);
  for (const char* system : {"/dev", "/proc", "/sys"}) {
    if (IsInside(resolved, system)) Refuse(r, resolved, std::string("it lies under ") + system);
  }
  std::error_code ec;
  const fs::file_status status = fs::status(resolved, ec);
  const bool exists = fs::exists(status);
  if (exists && !fs::is_regular_file(status) && !fs::is_directory(status)) {
    Refuse(r, resolved, "it is a device, FIFO or socket, not a file or folder");
  }
  for (const auto& db : r.databases) {
    const fs::path d = Canonical(db);
    for (const char* suffix : {"", "-wal", "-shm", "-journal"}) {
      if (resolved == fs::path(d.string() + suffix)) {
        Refuse(r, resolved, "it is the database " + d.string() + suffix);
      }
    }
  }
  if (IsSqliteFile(resolved)) Refuse(r, resolved, "it is a SQLite database");
  for (const std::string suffix : {"-wal", "-shm", "-journal"}) {
    const std::string name = resolved.string();
    if (name.size() > suffix.size() &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0 &&
        IsSqliteFile(name.substr(0, name.size() - suffix.size()))) {
      Refuse(r, resolved,
             "it is the journal of the database " + name.substr(0, name.size() - suffix.size()));
    }
  }
  if (const std::string why = InsideProtected(resolved, r); !why.empty()) Refuse(r, resolved, why);
  for (const auto& input : r.inputs) {
    if (const fs::path in = Canonical(input); IsInside(in, resolved)) {
      Refuse(r, resolved, in == resolved ? "it is the command's input"
                                         : "it holds the command's input " + in.string());
    }
  }
  if (!exists) return;
  const bool folder = fs::is_directory(status);
  if (r.kind == OutputRequest::Kind::kFile && folder) {
    Refuse(r, resolved, "it is a folder; the output is a file");
  }
  if (r.kind == OutputRequest::Kind::kFolder && !folder) {
    Refuse(r, resolved, "it is a file; the output is a folder");
  }
  if (folder && IsEmptyFolder(resolved)) return;
  if (!r.is_own_output || !r.is_own_output(resolved)) {
    Refuse(r, resolved,
           std::string(folder ? "the folder is not empty" : "the file exists") +
               " and is not an earlier output of this command");
  }
  if (!r.force) {
    Refuse(r, resolved, "it holds an earlier output of this command; --force replaces it",
           kOutputExists);
  }
}

}  // namespace doasido
