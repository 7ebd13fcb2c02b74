#include "ingest/host_slots.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <thread>

#include "core/error.h"

namespace doasido::ingest {
namespace {

int OpenLockFile(const std::filesystem::path& path) {
  std::filesystem::create_directories(path.parent_path());
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw Error("io", "cannot open lock file", {.file = path.string()});
  return fd;
}

// Host names may hold ':' or '[' (IPv6); keep file names plain.
std::string SafeName(const std::string& host) {
  std::string out;
  for (const char c : host) out += std::isalnum(static_cast<unsigned char>(c)) || c == '.' ||
                                           c == '-' ? c : '_';
  return out.empty() ? "_" : out;
}

}  // namespace

FileLock::FileLock(const std::filesystem::path& path) : fd_(OpenLockFile(path)) {
  while (::flock(fd_, LOCK_EX) != 0) {
    if (errno != EINTR) {
      ::close(fd_);
      fd_ = -1;
      throw Error("io", "cannot lock file", {.file = path.string()});
    }
  }
}

FileLock::FileLock(const std::filesystem::path& path, bool try_only) : fd_(OpenLockFile(path)) {
  if (::flock(fd_, try_only ? LOCK_EX | LOCK_NB : LOCK_EX) != 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // closing releases the flock
}

HostSlot::HostSlot(const std::filesystem::path& dir, const std::string& host, int max_per_host,
                   double poll_s) {
  const std::string name = SafeName(host);
  for (;;) {
    for (int i = 0; i < std::max(1, max_per_host); ++i) {
      auto lock =
          std::make_unique<FileLock>(dir / (name + "." + std::to_string(i) + ".lock"), true);
      if (lock->held()) {
        lock_ = std::move(lock);
        index_ = i;
        return;
      }
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(poll_s));
  }
}

}  // namespace doasido::ingest
