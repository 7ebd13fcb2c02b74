#include "tests/fuzz/fuzz_files.h"

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>

namespace doasido::fuzz {

const std::filesystem::path& ScratchDir() {
  static const std::filesystem::path dir = [] {
    const auto d = std::filesystem::temp_directory_path() /
                   ("doasido-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(ScratchDir(), ec);
    });
    return d;
  }();
  return dir;
}

std::filesystem::path WriteInput(const std::string& name, std::string_view bytes) {
  const auto path = ScratchDir() / name;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

std::vector<std::string_view> SplitParts(std::string_view bytes) {
  constexpr std::string_view kSeparator = "\n===\n";
  std::vector<std::string_view> parts;
  for (size_t at = bytes.find(kSeparator); at != std::string_view::npos;
       at = bytes.find(kSeparator)) {
    parts.push_back(bytes.substr(0, at));
    bytes.remove_prefix(at + kSeparator.size());
  }
  parts.push_back(bytes);
  return parts;
}

}  // namespace doasido::fuzz
