#include "core/whole_output.h"

#include <fcntl.h>  // AT_FDCWD
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>  // renameat2, RENAME_EXCHANGE
#include <cstring>
#include <fstream>
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

[[noreturn]] void Fail(const fs::path& temp, const fs::path& out, const std::string& what) {
  const std::string why = std::strerror(errno);
  std::error_code ec;
  fs::remove_all(temp, ec);
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

std::vector<fs::path> RemoveAbandonedTemporaries(const fs::path& folder) {
  std::vector<fs::path> removed;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string leaf = it->path().filename().string();
    std::smatch m;
    if (!std::regex_match(leaf, m, TempName()) || ProcessAlive(std::stol(m[1]))) continue;
    std::error_code rm;
    fs::remove_all(it->path(), rm);
    if (!rm) removed.push_back(it->path());
  }
  return removed;
}

bool ProcessAlive(long pid) {
  return pid > 0 && (kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH);
}

void WriteWhole(const fs::path& given, OutputKind kind,
                const std::function<void(const fs::path& temp)>& write,
                std::vector<fs::path>* removed) {
  const fs::path out = Plain(given);
  std::error_code ec;
  fs::create_directories(Parent(out), ec);
  // Whatever killed commands left in this folder is garbage.
  for (const fs::path& p : RemoveAbandonedTemporaries(Parent(out))) {
    if (removed) removed->push_back(p);
  }
  const fs::path temp = TempSibling(out);
  if (kind == OutputKind::kFolder && !fs::create_directory(temp, ec)) {
    throw Error("io", "cannot create a temporary folder: " + ec.message(), {.file = temp.string()});
  }
  try {
    write(temp);
  } catch (...) {
    fs::remove_all(temp, ec);
    throw;
  }
  if (kind == OutputKind::kFolder && fs::is_directory(fs::symlink_status(out, ec))) {
    if (renameat2(AT_FDCWD, temp.c_str(), AT_FDCWD, out.c_str(), RENAME_EXCHANGE) != 0) {
      Fail(temp, out, "cannot put the new output in place of the earlier one");
    }
    fs::remove_all(temp, ec);  // now the earlier output
    return;
  }
  if (std::rename(temp.c_str(), out.c_str()) != 0) Fail(temp, out, "cannot rename the output into place");
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
