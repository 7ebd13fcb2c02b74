#include "cli/output_options.h"

#include "core/config.h"
#include "core/file_text.h"

namespace doasido::cli {

namespace fs = std::filesystem;

void AddForceFlag(CLI::App& cmd, bool& force) {
  cmd.add_flag("--force", force,
               "Replace an earlier output of this command at the output path (nothing else is "
               "ever replaced: a database, a dataset version, the artifact folder, a device or "
               "another program's files are refused)");
}

std::function<bool(const fs::path&)> FolderHolds(std::vector<std::string> names) {
  return [names = std::move(names)](const fs::path& folder) {
    std::error_code ec;
    for (const auto& name : names) {
      if (fs::exists(folder / name, ec)) return true;
    }
    return false;
  };
}

bool HoldsHandModel(const fs::path& folder) {
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->path().extension() != ".json") continue;
    const Json j = Json::parse(TryReadFile(it->path()).value_or(""), nullptr, false);
    if (j.is_object() && j.contains("model") && j.contains("points")) return true;
  }
  return false;
}

std::function<bool(const fs::path&)> JsonOfFormat(std::string format) {
  return [format = std::move(format)](const fs::path& file) {
    const auto text = TryReadFile(file);
    if (!text) return false;
    const Json j = Json::parse(*text, nullptr, false);
    return j.is_object() && j.contains("format") && j["format"] == format;
  };
}

}  // namespace doasido::cli
