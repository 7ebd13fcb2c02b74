#include "core/whole_output.h"

#include <fcntl.h>  // AT_FDCWD
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>  // renameat2, RENAME_EXCHANGE
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <random>
#include <regex>

#include "core/error.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;

fs::path Parent(const fs::path& out) {
  return out.parent_path().empty() ? fs::path(".") : out.parent_path();
}

// `out` without a trailing separator, so "work/x/" names "x".
fs::path Plain(const fs::path& out) {
  return out.has_filename() ? out : out.parent_path();
}

// .<name>.tmp-<pid>-<hex>; the pid says whether its writer still runs.
const std::regex& TempName() {
  static const std::regex name(R"(\..+\.tmp-([0-9]+)-[0-9a-f]+)");
  return name;
}

constexpr const char* kMarkerSuffix = ".doasido-temporary";

// What the marker of `temp` holds: its own name, so a marker copied beside
// another file proves nothing.
std::string MarkerText(const fs::path& temp) {
  return "doasido temporary\n" + temp.filename().string() + "\n";
}

fs::path MarkerOf(const fs::path& temp) {
  return temp.parent_path() / (temp.filename().string() + kMarkerSuffix);
}

// True when `marker` is a regular file holding exactly `text` or, with
// `prefix`, the start of it (a marker whose writer was killed while writing
// it; its temporary was never made). A person's file of that name holds
// something else, or more.
bool Holds(const fs::path& marker, const std::string& text, bool prefix) {
  std::error_code ec;
  if (!fs::is_regular_file(fs::symlink_status(marker, ec))) return false;
  const std::uintmax_t size = fs::file_size(marker, ec);
  if (ec || size > text.size() || (!prefix && size != text.size())) return false;
  std::ifstream f(marker, std::ios::binary);
  std::string got(size, '\0');
  f.read(got.data(), static_cast<std::streamsize>(got.size()));
  return f.gcount() == static_cast<std::streamsize>(size) && text.compare(0, size, got) == 0;
}

// The writer of a temporary named `leaf` (with or without its marker
// suffix) when the name has our shape and a pid that can be one; nullopt
// for anything else (never an error: the folder is not ours alone).
std::optional<long> TempWriter(const std::string& leaf) {
  std::smatch m;
  if (!std::regex_match(leaf, m, TempName())) return std::nullopt;
  return ParsePid(m[1].str());
}

[[noreturn]] void Fail(const fs::path& temp, const fs::path& out, const std::string& what) {
  const std::string why = std::strerror(errno);
  std::error_code ec;
  fs::remove_all(temp, ec);
  UnmarkTemporary(temp);
  throw Error("io", what + ": " + why, {.file = out.string()});
}

}  // namespace

fs::path TempSibling(const fs::path& given) {
  const fs::path out = Plain(given);
  std::random_device rd;
  char tail[40];
  std::snprintf(tail, sizeof tail, "%ld-%08x", static_cast<long>(getpid()), rd());
  return Parent(out) / ("." + out.filename().string() + ".tmp-" + tail);
}

std::optional<long> ParsePid(const std::string& digits) {
  if (digits.empty() || digits.size() > 10) return std::nullopt;
  for (const char c : digits) {
    if (c < '0' || c > '9') return std::nullopt;
  }
  const long long pid = std::stoll(digits);  // at most 10 digits: no overflow
  if (pid <= 0 || pid > std::numeric_limits<pid_t>::max()) return std::nullopt;
  return static_cast<long>(pid);
}

void MarkTemporary(const fs::path& temp) {
  const fs::path marker = MarkerOf(temp);
  std::ofstream f(marker, std::ios::binary | std::ios::trunc);
  f << MarkerText(temp);
  f.close();
  if (!f) {
    throw Error("io", std::string("cannot write the temporary's marker: ") + std::strerror(errno),
                {.file = marker.string()});
  }
}

void UnmarkTemporary(const fs::path& temp) {
  std::error_code ec;
  fs::remove(MarkerOf(temp), ec);
}

// A temporary is removed only when its marker proves doasido made it and
// its writer is gone; a marker whose temporary is gone (killed between the
// rename and the marker's removal) goes too. Anything else of that shape is
// a person's and stays.
std::vector<fs::path> RemoveAbandonedTemporaries(const fs::path& folder) {
  std::vector<fs::path> removed;
  std::vector<fs::path> entries;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    entries.push_back(it->path());
  }
  const std::string suffix = kMarkerSuffix;
  for (const fs::path& path : entries) {
    std::string leaf = path.filename().string();
    const bool is_marker = leaf.size() > suffix.size() &&
                           leaf.compare(leaf.size() - suffix.size(), suffix.size(), suffix) == 0;
    if (is_marker) leaf.resize(leaf.size() - suffix.size());
    const fs::path temp = path.parent_path() / leaf;
    const std::optional<long> writer = TempWriter(leaf);
    if (!writer || ProcessAlive(*writer)) continue;
    if (is_marker && fs::exists(fs::symlink_status(temp, ec))) continue;  // removed with it
    if (!Holds(MarkerOf(temp), MarkerText(temp), /*prefix=*/is_marker)) continue;
    std::error_code rm;
    if (!is_marker) fs::remove_all(temp, rm);
    if (!rm) fs::remove(MarkerOf(temp), rm);
    if (!rm && !is_marker) removed.push_back(temp);
  }
  return removed;
}

bool ProcessAlive(long pid) {
  return pid > 0 && (kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH);
}

// Flushes `path` (a file, or every file below a folder) to the disk, so a
// full disk or a failing device shows here, before the rename, and not as
// a short file after it.
static void SyncToDisk(const fs::path& path, const fs::path& out) {
  std::error_code ec;
  if (fs::is_directory(fs::symlink_status(path, ec))) {
    for (fs::recursive_directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec)) {
      if (it->is_regular_file(ec)) SyncToDisk(it->path(), out);
    }
    if (ec) throw Error("io", "cannot list the new output: " + ec.message(), {.file = out.string()});
    return;
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 || ::fsync(fd) != 0) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) ::close(fd);
    throw Error("io", "cannot flush the new output to disk: " + why,
                {.file = path.string()});
  }
  ::close(fd);
}

void WriteWhole(const fs::path& given, OutputKind kind,
                const std::function<void(const fs::path& temp)>& write,
                std::vector<fs::path>* removed) {
  const fs::path out = Plain(given);
  std::error_code ec;
  fs::create_directories(Parent(out), ec);
  // Whatever killed commands left in this folder, and marked as theirs, is
  // garbage.
  for (const fs::path& p : RemoveAbandonedTemporaries(Parent(out))) {
    if (removed) removed->push_back(p);
  }
  const fs::path temp = TempSibling(out);
  MarkTemporary(temp);
  try {
    if (kind == OutputKind::kFolder && !fs::create_directory(temp, ec)) {
      throw Error("io", "cannot create a temporary folder: " + ec.message(),
                  {.file = temp.string()});
    }
    write(temp);
    if (!fs::exists(fs::symlink_status(temp, ec))) {
      throw Error("io", "the writer left no output", {.file = out.string()});
    }
    SyncToDisk(temp, out);
  } catch (...) {
    fs::remove_all(temp, ec);
    UnmarkTemporary(temp);
    throw;
  }
  if (kind == OutputKind::kFolder && fs::is_directory(fs::symlink_status(out, ec))) {
    if (renameat2(AT_FDCWD, temp.c_str(), AT_FDCWD, out.c_str(), RENAME_EXCHANGE) != 0) {
      Fail(temp, out, "cannot put the new output in place of the earlier one");
    }
    fs::remove_all(temp, ec);  // now the earlier output
    UnmarkTemporary(temp);
    return;
  }
  if (std::rename(temp.c_str(), out.c_str()) != 0) Fail(temp, out, "cannot rename the output into place");
  UnmarkTemporary(temp);
}

void WriteFileWhole(const fs::path& out, const std::string& bytes) {
  WriteWhole(out, OutputKind::kFile, [&](const fs::path& temp) {
    std::ofstream f(temp, std::ios::binary | std::ios::trunc);
    f << bytes;
    f.close();
    if (!f) throw Error("io", "cannot write", {.file = temp.string()});
  });
}

}  // namespace doasido
