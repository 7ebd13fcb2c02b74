#include "recon/bundle/model_command.h"

#include "core/bounded_text.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <deque>
#include <fstream>
#include <thread>

#include "core/child_groups.h"
#include "core/error.h"
#include "core/stage_progress.h"

namespace doasido::recon {

CommandOutcome RunModelCommand(const std::string& command, const std::filesystem::path& log,
                               double timeout_s, int tail_lines) {
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw Error("io", "cannot create the command log", {.file = log.string()});
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd);
    throw Error("io", "fork failed", {.file = log.string()});
  }
  if (pid == 0) {
    ::setpgid(0, 0);  // its own group, so a timeout kills every descendant
    ::dup2(fd, STDOUT_FILENO);
    ::dup2(fd, STDERR_FILENO);
    const int null_in = ::open("/dev/null", O_RDONLY);
    if (null_in >= 0) ::dup2(null_in, STDIN_FILENO);
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // also from here: no race with the child's own call
  AddChildGroup(pid);
  ::close(fd);
  CommandOutcome out;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  int status = 0;
  std::error_code ignored;
  std::uintmax_t log_size = 0;
  while (true) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    // A command that writes to its log is getting on (core/stage_progress.h).
    const std::uintmax_t size = std::filesystem::file_size(log, ignored);
    if (!ignored && size != log_size) {
      log_size = size;
      ReportStageProgress();
    }
    if (std::chrono::steady_clock::now() >= deadline) {
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      out.timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!out.timed_out) {
    if (WIFEXITED(status)) out.exit_code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) out.signal = WTERMSIG(status);
  }
  // Descendants that outlived a finished shell would hold the folder open.
  ::kill(-pid, SIGKILL);
  RemoveChildGroup(pid);
  out.log_tail = LogTail(log, tail_lines);
  return out;
}

std::string LogTail(const std::filesystem::path& log, int lines) {
  std::ifstream in(log);
  std::deque<std::string> last;
  std::string line;
  while (std::getline(in, line)) {
    last.push_back(line);
    if (static_cast<int>(last.size()) > lines) last.pop_front();
  }
  std::string out;
  for (const auto& l : last) out += (out.empty() ? "" : "\n") + l;
  // Lines are not bounded (a program may print one 9 MB line): bytes are.
  return BoundedTail(out, kMaxStoredTextBytes / 2, log.string());
}

}  // namespace doasido::recon
