// doasido slurm submit / resume against a real one-node Slurm cluster that
// the test starts on loopback (Debian's munge and slurm-wlm, installed by
// scripts/setup.sh; the daemons run as root from tests/slurm/slurm.conf.in
// and are stopped by their pids at the end): 200 synthetic clips in 4
// shards as an array job plus a merge job give the parent exactly what one
// machine's `doasido run` gives, after one task was cancelled mid-run and
// resumed, with every stage run done exactly once.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <thread>

#include "tests/db_dump.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::QueryRows;
using testing::ResultTables;
using testing::RunDoasido;
using testing::TempDir;

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

std::string Shell(const std::string& command) {
  std::string out;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  char buffer[4096];
  size_t n;
  while (pipe && (n = fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  if (pipe) pclose(pipe);
  return out;
}

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
  }
  return s;
}

// munged, slurmctld and slurmd for the lifetime of the object.
class SlurmCluster {
 public:
  explicit SlurmCluster(const std::filesystem::path& dir) : dir_(dir) {
    for (const char* sub : {"state", "spool"}) std::filesystem::create_directories(dir / sub);
    std::string conf = testing::ReadFile(testing::SourceDir() / "tests/slurm/slurm.conf.in");
    conf = Replace(conf, "@DIR@", dir.string());
    conf = Replace(conf, "@CTLD_PORT@", std::to_string(FreePort()));
    conf = Replace(conf, "@SLURMD_PORT@", std::to_string(FreePort()));
    conf = Replace(conf, "@CPUS@", std::to_string(std::thread::hardware_concurrency()));
    testing::WriteFile(dir / "slurm.conf", conf);
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
  ~SlurmCluster() {
    for (const char* pid_file : {"slurmd.pid", "slurmctld.pid", "munged.pid"}) {
      std::ifstream in(dir_ / pid_file);
      pid_t pid = 0;
      if (in >> pid && pid > 0) kill(pid, SIGTERM);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  // True once the node takes jobs.
  bool WaitIdle(double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      if (Shell("sinfo -h -o %t").find("idle") != std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
    return false;
  }
  // Waits until no job is queued or running.
  bool WaitEmpty(double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      if (Shell("squeue -h -o %i").empty()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
    return false;
  }
  std::string Logs() const {
    return log_ + testing::ReadFile(dir_ / "slurmctld.log") + testing::ReadFile(dir_ / "slurmd.log");
  }

 private:
  std::filesystem::path dir_;
  std::string log_;
};

TEST(Slurm, ArrayAndMergeEqualOneMachineAfterACancelledTaskIsResumed) {
  ASSERT_EQ(geteuid(), 0u) << "the test starts slurmctld and slurmd as root";
  TempDir dir;
  SlurmCluster cluster(dir / "slurm");
  ASSERT_TRUE(cluster.WaitIdle(60)) << cluster.Logs();

  const std::string pool = (dir / "pool").string();
  ASSERT_EQ(RunDoasido({"synth", "--out", pool, "--clips", "200", "--frames", "30", "--width",
                        "96", "--height", "72", "--seed", "3", "--no-bundles"})
                .exit_code,
            0);
  auto ingested = [&](const std::string& name) {
    const auto db = dir / name / "doasido.db";
    std::filesystem::create_directories(db.parent_path());
    EXPECT_EQ(RunDoasido({"init", "--db", db.string()}).exit_code, 0);
    EXPECT_EQ(RunDoasido({"ingest", "--db", db.string(), pool + "/Annotations"}).exit_code, 0);
    return db;
  };
  const auto single = ingested("single");
  ASSERT_EQ(RunDoasido({"run", "--db", single.string(), "--jobs", "2"}).exit_code, 0);

  const auto parent = ingested("parent");
  const auto submit = RunDoasido({"slurm", "submit", "--db", parent.string(), "--shards", "4",
                                  "--cpus-per-task", "1", "--time", "00:30:00"});
  ASSERT_EQ(submit.exit_code, 0) << submit.err << cluster.Logs();
  std::smatch m;
  ASSERT_TRUE(std::regex_search(submit.out, m, std::regex("array job (\\d+)"))) << submit.out;
  const std::string array = m[1];

  // Cancel task 0 once its shard has started but not finished.
  const auto shard0 = dir / "parent/shards/shard-000/doasido.db";
  bool cancelled = false;
  for (int i = 0; i < 1200 && !cancelled; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (!std::filesystem::exists(shard0)) continue;
    const auto done = QueryRows(shard0, "SELECT COUNT(*) FROM stage_runs WHERE state = 'done'");
    if (!done.empty() && std::stoi(done[0]) >= 3) {
      Shell("scancel " + array + "_0");
      cancelled = true;
    }
  }
  ASSERT_TRUE(cancelled);
  ASSERT_TRUE(cluster.WaitEmpty(300)) << Shell("squeue") << cluster.Logs();
  const auto open = QueryRows(shard0, "SELECT COUNT(*) FROM stage_runs WHERE state IN"
                                      " ('pending', 'running')");
  ASSERT_GT(std::stoi(open[0]), 0) << "task 0 finished before it could be cancelled";
  const auto status = RunDoasido({"status", "--db", parent.string()});
  EXPECT_NE(status.out.find("shard-000"), std::string::npos) << status.out;

  const auto resume = RunDoasido({"slurm", "resume", "--db", parent.string()});
  ASSERT_EQ(resume.exit_code, 0) << resume.err;
  EXPECT_NE(resume.out.find("(tasks 0)"), std::string::npos) << resume.out;
  ASSERT_TRUE(cluster.WaitEmpty(300)) << Shell("squeue") << cluster.Logs();

  EXPECT_EQ(ResultTables(parent), ResultTables(single));
  EXPECT_EQ(QueryRows(parent, "SELECT COUNT(*) FROM stage_runs WHERE state <> 'done'")[0], "0");
  // Nothing lost or done twice: one 'done' event per stage run.
  EXPECT_EQ(QueryRows(parent, "SELECT clip_id, stage FROM events WHERE kind = 'done'"
                              " GROUP BY 1, 2 HAVING COUNT(*) <> 1"),
            std::vector<std::string>{});
  EXPECT_EQ(QueryRows(parent, "SELECT COUNT(DISTINCT clip_id || stage) FROM events"
                              " WHERE kind = 'done'"),
            QueryRows(parent, "SELECT COUNT(*) FROM stage_runs"));
}

}  // namespace
}  // namespace doasido
