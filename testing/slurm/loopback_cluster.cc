#include "testing/slurm/loopback_cluster.h"

#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <thread>

#include "core/file_text.h"

namespace doasido::testing {
namespace {

int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  close(fd);
  return ntohs(addr.sin_port);
}

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
  }
  return s;
}

std::string Slurp(const std::filesystem::path& path) { return TryReadFile(path).value_or(""); }

// Polls `done` every 250 ms for up to `seconds`.
template <typename Done>
bool WaitFor(double seconds, Done done) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  }
  return false;
}

}  // namespace

std::string Shell(const std::string& command) {
  std::string out;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  char buffer[4096];
  size_t n;
  while (pipe && (n = fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  if (pipe) pclose(pipe);
  return out;
}

LoopbackSlurm::LoopbackSlurm(const std::filesystem::path& dir) : dir_(dir) {
  for (const char* sub : {"state", "spool"}) std::filesystem::create_directories(dir / sub);
  std::string conf = Slurp(std::filesystem::path(DOASIDO_SOURCE_DIR) / "testing/slurm/slurm.conf.in");
  conf = Replace(conf, "@DIR@", dir.string());
  conf = Replace(conf, "@CTLD_PORT@", std::to_string(FreePort()));
  conf = Replace(conf, "@SLURMD_PORT@", std::to_string(FreePort()));
  conf = Replace(conf, "@CPUS@", std::to_string(std::thread::hardware_concurrency()));
  std::ofstream(dir / "slurm.conf") << conf;
  std::ofstream(dir / "gres.conf") << "NodeName=localhost Name=gpu File=/dev/null\n";
  setenv("SLURM_CONF", (dir / "slurm.conf").c_str(), 1);
  {
    std::ofstream key(dir / "munge.key", std::ios::binary);
    std::ifstream random("/dev/urandom", std::ios::binary);
    std::string bytes(1024, '\0');
    random.read(bytes.data(), 1024);
    key << bytes;
  }
  std::filesystem::permissions(dir / "munge.key", std::filesystem::perms::owner_read);
  const std::string d = dir.string();
  log_ += Shell("munged --force --key-file=" + d + "/munge.key --socket=" + d +
                "/munge.socket --pid-file=" + d + "/munged.pid --log-file=" + d +
                "/munged.log --seed-file=" + d + "/munged.seed");
  log_ += Shell("slurmctld -c");
  log_ += Shell("slurmd");
}

LoopbackSlurm::~LoopbackSlurm() {
  for (const char* pid_file : {"slurmd.pid", "slurmctld.pid", "munged.pid"}) {
    std::ifstream in(dir_ / pid_file);
    pid_t pid = 0;
    if (in >> pid && pid > 0) kill(pid, SIGTERM);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
}

bool LoopbackSlurm::WaitIdle(double seconds) const {
  return WaitFor(seconds,
                 [] { return Shell("sinfo -h -o %t").find("idle") != std::string::npos; });
}

bool LoopbackSlurm::WaitEmpty(double seconds) const {
  return WaitFor(seconds, [] { return Shell("squeue -h -o %i").empty(); });
}

std::string LoopbackSlurm::Logs() const {
  return log_ + Slurp(dir_ / "slurmctld.log") + Slurp(dir_ / "slurmd.log");
}

}  // namespace doasido::testing
