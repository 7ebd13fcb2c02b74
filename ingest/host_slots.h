// Cross-process limits for downloads, with lock files (flock) in a folder
// every worker of a database shares: the kernel drops a lock when its
// process dies, so a crashed worker never holds a slot.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

namespace doasido::ingest {

// An exclusive flock on one file, held for the object's lifetime.
class FileLock {
 public:
  // Blocks until the lock on `path` (created if needed) is held. Throws
  // Error("io") naming the file when it cannot be opened.
  explicit FileLock(const std::filesystem::path& path);
  // Takes the lock only if it is free now; held() says whether it was.
  FileLock(const std::filesystem::path& path, bool try_only);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

// One of `max_per_host` slots of `host`: files <dir>/<host>.<i>.lock. The
// constructor waits (polling every `poll_s`) until a slot is free, so at
// most max_per_host transfers from one host run at once across all
// processes that use `dir`.
class HostSlot {
 public:
  HostSlot(const std::filesystem::path& dir, const std::string& host, int max_per_host,
           double poll_s = 0.05);
  int index() const { return index_; }

 private:
  std::unique_ptr<FileLock> lock_;
  int index_ = -1;
};

}  // namespace doasido::ingest
