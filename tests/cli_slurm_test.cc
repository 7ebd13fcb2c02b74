// doasido slurm submit / resume against a real one-node Slurm cluster that
// the test starts on loopback (Debian's munge and slurm-wlm, installed by
// scripts/setup.sh; the daemons run as root from tests/slurm/slurm.conf.in
// and are stopped by their pids at the end): 200 synthetic clips in 4
// shards as an array job plus a merge job give the parent exactly what one
// machine's `doasido run` gives, after one task was cancelled mid-run and
// resumed, with every stage run done exactly once.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <regex>
#include <thread>

#include "tests/db_dump.h"
#include "tests/slurm/loopback_cluster.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::LoopbackSlurm;
using testing::QueryRows;
using testing::ResultTables;
using testing::RunDoasido;
using testing::Shell;
using testing::TempDir;

TEST(Slurm, ArrayAndMergeEqualOneMachineAfterACancelledTaskIsResumed) {
  ASSERT_EQ(geteuid(), 0u) << "the test starts slurmctld and slurmd as root";
  TempDir dir;
  LoopbackSlurm cluster(dir / "slurm");
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
