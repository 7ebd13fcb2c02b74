// doasido slurm submit / resume against a real one-node Slurm cluster that
// the test starts on loopback (Debian's munge and slurm-wlm, installed by
// scripts/setup.sh; the daemons run as root from testing/slurm/slurm.conf.in
// and are stopped by their pids at the end): 200 synthetic clips in 4
// shards as an array job plus a merge job give the parent exactly what one
// machine's `doasido run` gives, after one task was cancelled mid-run and
// resumed, with every stage run done exactly once. Then the same with three
// stage groups on their own resources (filters on the default partition, the
// model stage on partition gpu with the node's one GRES gpu, recon ->
// retarget_kinematic back on the default), the filters' task of one shard
// cancelled midway and resumed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <regex>
#include <thread>

#include "testing/db_dump.h"
#include "testing/slurm/loopback_cluster.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::LoopbackSlurm;
using testing::QueryRows;
using testing::ResultTables;
using testing::RunDoasido;
using testing::Shell;
using testing::TempDir;

// Cancels task 0 of array job `array` once its shard (database `shard0`)
// has finished 3 stage runs, so it stops with work left; false when that
// never happened within a minute.
bool CancelTaskZeroMidRun(const std::filesystem::path& shard0, const std::string& array) {
  for (int i = 0; i < 1200; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (!std::filesystem::exists(shard0)) continue;
    const auto done = QueryRows(shard0, "SELECT COUNT(*) FROM stage_runs WHERE state = 'done'");
    if (!done.empty() && std::stoi(done[0]) >= 3) {
      Shell("scancel " + array + "_0");
      return true;
    }
  }
  return false;
}

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
    EXPECT_EQ(RunDoasido({"init", "--db", db.string(), "--pipeline", "filters"}).exit_code, 0);
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
  ASSERT_TRUE(CancelTaskZeroMidRun(shard0, array));
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

// The result tables with what legitimately differs between two databases
// taken out: absolute paths up to a clip's artifact folder (the shard's
// folder, not the parent's) and wall times (the bundle stage's seconds, the
// hand detector's milliseconds).
std::vector<std::vector<std::string>> ComparableTables(const std::filesystem::path& db) {
  static const std::regex kRoot("/[^\"|]*/artifacts/");
  static const std::regex kSeconds("\"(seconds|ms|ms_per_sample)\":[-0-9.e+]+");
  auto tables = ResultTables(db);
  for (auto& table : tables) {
    for (auto& row : table) {
      row = std::regex_replace(std::regex_replace(row, kRoot, "<db>/artifacts/"), kSeconds,
                               "\"$1\":_");
    }
  }
  return tables;
}

TEST(Slurm, StageGroupsOnTheirOwnResourcesEqualOneMachineAfterAGroupTaskIsResumed) {
  ASSERT_EQ(geteuid(), 0u) << "the test starts slurmctld and slurmd as root";
  TempDir dir;
  LoopbackSlurm cluster(dir / "slurm");
  ASSERT_TRUE(cluster.WaitIdle(60)) << cluster.Logs();

  const auto pool = dir / "pool";
  ASSERT_EQ(RunDoasido({"synth", "--out", pool.string(), "--clips", "12", "--frames", "24",
                        "--width", "96", "--height", "72", "--mix", "clean=1", "--seed", "7",
                        "--no-annotations"})
                .exit_code,
            0);
  const std::string pipeline =
      "probe,filters_analyze,shot_boundary,out_of_frame,activity,bundle,recon,retarget_kinematic";
  const auto config = dir / "models.toml";
  doasido::testing::WriteFile(config, "[bundle]\nserver = \"/usr/bin/python3 " +
                                          (doasido::testing::SourceDir() / "tools/bundle_server.py").string() +
                                          " --load-s 0.2\"\n");
  auto ingested = [&](const std::string& name) {
    const auto db = dir / name / "doasido.db";
    std::filesystem::create_directories(db.parent_path());
    EXPECT_EQ(RunDoasido({"init", "--db", db.string(), "--pipeline", pipeline}).exit_code, 0);
    EXPECT_EQ(RunDoasido({"ingest", "--db", db.string(), (pool / "clips.csv").string()}).exit_code, 0);
    return db;
  };
  const auto single = ingested("single");
  const auto one = RunDoasido({"run", "--db", single.string(), "--jobs", "2", "--config", config.string()});
  ASSERT_EQ(one.exit_code, 0) << one.err;
  ASSERT_GT(std::stoi(QueryRows(single, "SELECT COUNT(*) FROM stage_runs WHERE stage ="
                                        " 'retarget_kinematic' AND state = 'done'")[0]),
            0)
      << "no clip reached the last group";

  const auto parent = ingested("parent");
  const auto submit = RunDoasido(
      {"slurm", "submit", "--db", parent.string(), "--shards", "4", "--config", config.string(),
       "--time", "00:30:00", "--group", "probe..activity name=filters", "--group",
       "bundle name=gpu partition=gpu gpus=1", "--group", "recon..retarget_kinematic name=recon"});
  ASSERT_EQ(submit.exit_code, 0) << submit.err << cluster.Logs();
  std::smatch m;
  ASSERT_TRUE(std::regex_search(submit.out, m, std::regex("group filters: array job (\\d+)")))
      << submit.out;
  const std::string filters = m[1];
  ASSERT_TRUE(std::regex_search(submit.out, m, std::regex("group gpu: array job (\\d+)")));
  const std::string gpu = m[1];
  EXPECT_NE(submit.out.find("aftercorr:" + filters), std::string::npos) << submit.out;
  // The model group asked for its partition and the node's GRES.
  const std::string gpu_job = Shell("scontrol show job " + gpu);
  EXPECT_NE(gpu_job.find("Partition=gpu"), std::string::npos) << gpu_job;
  EXPECT_NE(gpu_job.find("gres:gpu:1"), std::string::npos) << gpu_job;

  // Cancel the filters' task 0 once its shard has started but not finished.
  const auto shard0 = dir / "parent/shards/shard-000/doasido.db";
  ASSERT_TRUE(CancelTaskZeroMidRun(shard0, filters));
  // The other shards go through all groups; shard 0's later tasks wait forever.
  bool settled = false;
  for (int i = 0; i < 1200 && !settled; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    const std::string queue = Shell("squeue -h -r -o '%i %T %r'");
    settled = queue.find("RUNNING") == std::string::npos &&
              queue.find(gpu + "_0 PENDING DependencyNeverSatisfied") != std::string::npos &&
              std::count(queue.begin(), queue.end(), '\n') == 3;  // gpu_0, recon_0, merge
  }
  ASSERT_TRUE(settled) << Shell("squeue -r") << cluster.Logs();
  const auto status = RunDoasido({"status", "--db", parent.string()});
  EXPECT_NE(status.out.find("gpu:PENDING"), std::string::npos) << status.out;

  const auto resume = RunDoasido({"slurm", "resume", "--db", parent.string()});
  ASSERT_EQ(resume.exit_code, 0) << resume.err;
  EXPECT_NE(resume.out.find("resubmitting task 0 (shard-000) from group filters"),
            std::string::npos)
      << resume.out;
  EXPECT_NE(resume.out.find("(tasks 0)"), std::string::npos) << resume.out;
  ASSERT_TRUE(cluster.WaitEmpty(300)) << Shell("squeue") << cluster.Logs();

  EXPECT_EQ(ComparableTables(parent), ComparableTables(single));
  EXPECT_EQ(QueryRows(parent, "SELECT COUNT(*) FROM stage_runs WHERE state NOT IN ('done')")[0],
            QueryRows(single, "SELECT COUNT(*) FROM stage_runs WHERE state NOT IN ('done')")[0]);
  EXPECT_EQ(QueryRows(parent, "SELECT clip_id, stage FROM events WHERE kind = 'done'"
                              " GROUP BY 1, 2 HAVING COUNT(*) <> 1"),
            std::vector<std::string>{});
}

}  // namespace
}  // namespace doasido
