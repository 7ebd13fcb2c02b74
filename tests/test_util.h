// Helpers shared by the test executables: where the real sample data is,
// fresh temporary folders, and running the doasido binary.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace doasido::testing {

// ../shared/data beside the checkout (absolute).
std::filesystem::path SharedData();
// The built doasido executable.
std::filesystem::path DoasidoBin();
// The repository root.
std::filesystem::path SourceDir();

// A fresh, empty directory removed when the object goes away (kept when
// DOASIDO_KEEP_TMP is set, for debugging).
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

struct CommandResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs the doasido binary with `args` (no shell), capturing both streams.
CommandResult RunDoasido(const std::vector<std::string>& args);

// Runs `command` through /bin/sh and returns its standard output; a
// non-zero exit status is a test failure (EXPECT).
std::string ShellOk(const std::string& command);

// The synthetic pools' stand-in bundle model: a `[bundle]` config section
// whose command copies the synthetic bundle of the clip's video.
std::string SyntheticBundleConfig();
// `doasido synth --out out --clips N --seed S --frames F --width W --height H
// --mix mix`, asserting success (EXPECT).
void SynthPool(const std::filesystem::path& out, int clips, int seed, int frames, int width,
               int height, const std::string& mix);

// Writes `text` to `path`, creating parent folders.
void WriteFile(const std::filesystem::path& path, const std::string& text);
std::string ReadFile(const std::filesystem::path& path);
// Every record of a CSV file the project wrote (header included), through
// the one reader (core/csv.h); none for a file that is not there.
std::vector<std::vector<std::string>> ReadCsv(const std::filesystem::path& path);

// Starts `args` (argv[0] looked up in PATH) with stdout and stderr to
// `log`; returns its pid.
int Spawn(const std::vector<std::string>& args, const std::filesystem::path& log);
// Waits for `pid`; its exit status, or 128 + the signal that ended it.
int WaitFor(int pid);
// The id of a process that has ended (forked, exited and reaped here): a
// writer or lease holder that is gone.
long DeadPid();
// A loopback-only LCM multicast URL (ttl=0) on a port of this process's
// own, so parallel test runs do not hear each other.
std::string LoopbackLcmUrl();

// The code of the doasido::Error `f` throws, or "no error".
std::string ErrorCode(const std::function<void()>& f);

}  // namespace doasido::testing
