#include "dataset/whole_output.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <random>
#include <regex>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include "core/error.h"

namespace doasido::dataset {
namespace {

namespace fs = std::filesystem;

std::string TempName(const fs::path& out) {
  std::random_device rd;
  char buf[64];
  std::snprintf(buf, sizeof buf, ".tmp-%d-%08x", static_cast<int>(getpid()), rd());
  return "." + out.filename().string() + buf;
}

bool ProcessGone(pid_t pid) { return kill(pid, 0) != 0 && errno == ESRCH; }

// Removes .<name>.tmp-<pid>-<hex> siblings of `out` whose process is gone.
void RemoveAbandoned(const fs::path& out, std::vector<fs::path>* removed) {
  const fs::path dir = out.parent_path().empty() ? fs::path(".") : out.parent_path();
  const std::string prefix = "." + out.filename().string() + ".tmp-";
  static const std::regex tail("([0-9]+)-[0-9a-f]+");
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string leaf = entry.path().filename().string();
    std::smatch m;
    const std::string rest = leaf.rfind(prefix, 0) == 0 ? leaf.substr(prefix.size()) : "";
    if (rest.empty() || !std::regex_match(rest, m, tail)) continue;
    if (!ProcessGone(static_cast<pid_t>(std::stol(m[1])))) continue;
    fs::remove_all(entry.path(), ec);
    if (removed) removed->push_back(entry.path());
  }
}

}  // namespace

void WriteWhole(const fs::path& out, bool folder, const std::string& marker,
                const std::function<void(const fs::path& temp)>& write,
                std::vector<fs::path>* removed) {
  std::error_code ec;
  if (out.has_parent_path()) fs::create_directories(out.parent_path(), ec);
  RemoveAbandoned(out, removed);
  const bool exists = fs::exists(fs::symlink_status(out, ec));
  if (exists && folder) {
    if (!fs::is_directory(out, ec)) {
      throw Error("output_exists", "the export's --out is a file, not a folder", {.file = out.string()});
    }
    if (!fs::is_empty(out, ec) && !fs::exists(out / marker, ec)) {
      throw Error("output_exists",
                  "the folder is not empty and holds no " + marker +
                      ", so it is no complete export this command would replace",
                  {.file = out.string()});
    }
  }
  if (exists && !folder && !fs::is_regular_file(out, ec)) {
    throw Error("output_exists", "the export's --out exists and is not a file", {.file = out.string()});
  }
  const fs::path temp = (out.parent_path().empty() ? fs::path(".") : out.parent_path()) / TempName(out);
  try {
    write(temp);
  } catch (...) {
    fs::remove_all(temp, ec);
    throw;
  }
  // Folders: swap in one step, then remove the old export (now at temp).
  if (exists && folder) {
    if (renameat2(AT_FDCWD, temp.c_str(), AT_FDCWD, out.c_str(), RENAME_EXCHANGE) != 0) {
      const int err = errno;
      fs::remove_all(temp, ec);
      throw Error("io", std::string("cannot swap the export into place: ") + std::strerror(err),
                  {.file = out.string()});
    }
    fs::remove_all(temp, ec);
    return;
  }
  if (std::rename(temp.c_str(), out.c_str()) != 0) {
    const int err = errno;
    fs::remove_all(temp, ec);
    throw Error("io", std::string("cannot rename the export into place: ") + std::strerror(err),
                {.file = out.string()});
  }
}

}  // namespace doasido::dataset
