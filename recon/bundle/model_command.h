// Running a model's command line for one clip: /bin/sh in its own process
// group, stdout and stderr to a log file, killed (the whole group) when it
// outlives its wall-clock budget.
#pragma once

#include <filesystem>
#include <string>

namespace doasido::recon {

struct CommandOutcome {
  bool timed_out = false;
  int exit_code = -1;     // WEXITSTATUS, or -1 when killed by a signal / timed out
  int signal = 0;         // terminating signal, 0 when it exited
  std::string log_tail;   // the last lines of the combined stdout/stderr log
};

// Runs `command` with /bin/sh -c, output appended to `log`. Throws
// Error("io") when the process cannot be started.
CommandOutcome RunModelCommand(const std::string& command, const std::filesystem::path& log,
                               double timeout_s, int tail_lines);

// The last `lines` lines of a log file ("" when it cannot be read).
std::string LogTail(const std::filesystem::path& log, int lines);

}  // namespace doasido::recon
