// The artifact root's placement lock: merges hold it exclusively while
// their rows and folders disagree, readers of artifacts hold it shared
// (db/database.h, LockForReading).
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "core/error.h"
#include "db/database.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;

// The lock file's descriptor, or -1 where there is none to take (no root
// yet, or a read-only one).
int OpenLockFile(const fs::path& root) {
  std::error_code ec;
  if (root.empty() || !fs::is_directory(root, ec)) return -1;
  const fs::path file = root / Database::kPlacementLockFile;
  int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  return fd;
}

// Takes `how` on `fd`, saying `waiting` on stderr when it has to wait.
void Take(int fd, int how, const std::string& waiting, const fs::path& root) {
  if (::flock(fd, how | LOCK_NB) == 0) return;
  if (errno != EWOULDBLOCK) {
    throw Error("io", std::string("cannot lock the artifact root: ") + std::strerror(errno),
                {.file = (root / Database::kPlacementLockFile).string()});
  }
  std::fprintf(stderr, "%s\n", waiting.c_str());
  while (::flock(fd, how) != 0) {
    if (errno != EINTR) {
      throw Error("io", std::string("cannot lock the artifact root: ") + std::strerror(errno),
                  {.file = (root / Database::kPlacementLockFile).string()});
    }
  }
}

}  // namespace

Database::ArtifactLock::~ArtifactLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

Database::ArtifactLock Database::LockForReading() {
  for (;;) {
    const int fd = OpenLockFile(artifact_root_);
    if (fd < 0) return ArtifactLock();
    ArtifactLock lock(fd);
    Take(fd, LOCK_SH,
         "waiting for a merge into " + artifact_root_.string() + " to place its folders", artifact_root_);
    if (!GetMeta(kPlacementKey)) return lock;
    // A journal while no merge holds the lock: its merge died. Finish it
    // (exclusively), then read.
    Take(fd, LOCK_EX, "waiting for other readers to finish a killed merge", artifact_root_);
    FinishPlacement(/*own=*/true);
  }
}

Database::ArtifactLock Database::LockForPlacement() {
  const int fd = OpenLockFile(artifact_root_);
  if (fd < 0) return ArtifactLock();
  ArtifactLock lock(fd);
  Take(fd, LOCK_EX,
       "waiting for readers of " + artifact_root_.string() +
           " (dataset create, deploy plan) to finish before merging",
       artifact_root_);
  return lock;
}

}  // namespace doasido
