#include "core/tree_copy.h"

namespace doasido {

namespace fs = std::filesystem;

void CopyTreeAsOurs(const fs::path& from, const fs::path& to, std::error_code& ec) {
  fs::create_directories(to, ec);
  if (ec) return;
  fs::recursive_directory_iterator it(from, fs::directory_options::follow_directory_symlink, ec);
  for (; !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    const fs::path target = to / it->path().lexically_relative(from);
    if (it->is_directory(ec)) {
      fs::create_directory(target, ec);
    } else if (!ec && fs::copy_file(it->path(), target, ec)) {
      fs::permissions(target, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::add, ec);
    }
  }
}

}  // namespace doasido
