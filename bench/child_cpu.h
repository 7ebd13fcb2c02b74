// CPU time of commands a benchmark runs, for figures "per CPU second" that
// hold on a busy machine.
#pragma once

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

namespace doasido::bench {

inline double Seconds(const timeval& t) {
  return static_cast<double>(t.tv_sec) + t.tv_usec * 1e-6;
}

// User + system seconds of this process so far (all its threads).
inline double SelfCpu() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return Seconds(u.ru_utime) + Seconds(u.ru_stime);
}

// User + system seconds of `argv` (looked up on PATH) and every child it
// waited for, from wait4; its output goes to /dev/null. -1 when it fails.
inline double ChildCpu(const std::vector<std::string>& argv) {
  std::fflush(stdout);  // or the child flushes our buffered lines a second time
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    std::freopen("/dev/null", "w", stdout);
    std::freopen("/dev/null", "w", stderr);
    execvp(args[0], args.data());
    _exit(127);
  }
  int status = 0;
  rusage u{};
  wait4(pid, &status, 0, &u);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return -1;
  return Seconds(u.ru_utime) + Seconds(u.ru_stime);
}

// ffmpeg's scene-change filter over `file`, the filters' peer.
inline double FfmpegSceneCpu(const std::string& file) {
  return ChildCpu({"ffmpeg", "-hide_banner", "-nostdin", "-i", file, "-vf",
                   "select='gt(scene,0.3)'", "-f", "null", "-"});
}

}  // namespace doasido::bench
