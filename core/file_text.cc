#include "core/file_text.h"

#include <fstream>
#include <sstream>

#include "core/error.h"

namespace doasido {

std::optional<std::string> TryReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return std::move(bytes).str();
}

std::string ReadFileOrThrow(const std::filesystem::path& path, const std::string& code,
                            const std::string& message, const std::string& label) {
  std::optional<std::string> bytes = TryReadFile(path);
  if (!bytes) throw Error(code, message, {.file = label.empty() ? path.string() : label});
  return std::move(*bytes);
}

}  // namespace doasido
