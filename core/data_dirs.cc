#include "core/data_dirs.h"

#include <cstdlib>

namespace doasido {

std::filesystem::path ExecutableDir() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::current_path() : exe.parent_path();
}

std::filesystem::path DataDir(const std::string& name, const char* env_var) {
  if (const char* given = std::getenv(env_var); given != nullptr && *given != '\0') {
    return given;
  }
  return (ExecutableDir() / ".." / "share" / "doasido" / name).lexically_normal();
}

std::filesystem::path NpmDir() {
  if (const char* dir = std::getenv("DOASIDO_NPM_DIR"); dir != nullptr && *dir != '\0') return dir;
  const char* home = std::getenv("HOME");
  return std::filesystem::path(home ? home : "/root") / ".cache/doasido/npm";
}

}  // namespace doasido
