#include "tests/test_util.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <random>
#include <stdexcept>

#include "core/csv.h"
#include "core/error.h"
#include "core/file_text.h"

namespace doasido::testing {

std::filesystem::path SharedData() { return DOASIDO_SHARED_DATA; }
std::filesystem::path DoasidoBin() { return DOASIDO_BIN; }
std::filesystem::path SourceDir() { return DOASIDO_SOURCE_DIR; }

TempDir::TempDir() {
  std::random_device rd;
  path_ = std::filesystem::temp_directory_path() /
          ("doasido-test-" + std::to_string(getpid()) + "-" + std::to_string(rd()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  if (std::getenv("DOASIDO_KEEP_TMP") == nullptr) {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
}

CommandResult RunDoasido(const std::vector<std::string>& args) {
  char out_name[] = "/tmp/doasido-out-XXXXXX";
  char err_name[] = "/tmp/doasido-err-XXXXXX";
  const int out_fd = mkstemp(out_name);
  const int err_fd = mkstemp(err_name);
  if (out_fd < 0 || err_fd < 0) throw std::runtime_error("mkstemp failed");
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out_fd, STDOUT_FILENO);
    dup2(err_fd, STDERR_FILENO);
    std::vector<std::string> argv_store = {DoasidoBin().string()};
    argv_store.insert(argv_store.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_store) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  close(out_fd);
  close(err_fd);
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = ReadFile(out_name);
  result.err = ReadFile(err_name);
  std::filesystem::remove(out_name);
  std::filesystem::remove(err_name);
  return result;
}

std::string SyntheticBundleConfig() {
  return "[bundle]\ncommand = \"cp -r $(dirname $(dirname {video}))/bundles/$(basename "
         "{video} .mp4)/. {output}/\"\n";
}

void SynthPool(const std::filesystem::path& out, int clips, int seed, int frames, int width,
               int height, const std::string& mix) {
  const CommandResult r =
      RunDoasido({"synth", "--out", out.string(), "--clips", std::to_string(clips), "--seed",
                  std::to_string(seed), "--frames", std::to_string(frames), "--width",
                  std::to_string(width), "--height", std::to_string(height), "--mix", mix});
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

void WriteFile(const std::filesystem::path& path, const std::string& text) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string ReadFile(const std::filesystem::path& path) {
  return TryReadFile(path).value_or("");
}

std::vector<std::vector<std::string>> ReadCsv(const std::filesystem::path& path) {
  std::vector<std::vector<std::string>> rows;
  if (!std::filesystem::exists(path)) return rows;
  CsvReader reader = CsvReader::Open(path, "bad_csv");
  CsvRecord record;
  while (reader.Next(record)) {
    EXPECT_EQ(record.error, "") << path << ":" << record.line;
    rows.push_back(record.fields);
  }
  return rows;
}

std::string ShellOk(const std::string& command) {
  std::string out;
  FILE* p = popen(command.c_str(), "r");
  char buf[4096];
  size_t n;
  while (p && (n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  EXPECT_EQ(p ? pclose(p) : -1, 0) << command;
  return out;
}

int Spawn(const std::vector<std::string>& args, const std::filesystem::path& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

int WaitFor(int pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

long DeadPid() {
  const pid_t pid = fork();
  if (pid == 0) _exit(0);
  WaitFor(pid);
  return pid;
}

std::string LoopbackLcmUrl() {
  return "udpm://239.255.76.67:" + std::to_string(7700 + getpid() % 2000) + "?ttl=0";
}

std::string ErrorCode(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.code();
  }
  return "no error";
}

}  // namespace doasido::testing
