// doasido shard / merge without Slurm: the same clips run in shards and
// merged back give the parent exactly what one machine's run gives; a second
// merge changes nothing; a partly done shard merges its done part; a shard
// of another database, or run with other parameters, is refused by name.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include <filesystem>

#include "testing/db_dump.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::QueryRows;
using testing::ResultTables;
using testing::RunDoasido;
using testing::TempDir;

// Every table of a database with row ids, for "nothing changed" checks.
std::vector<std::vector<std::string>> AllRows(const std::filesystem::path& db) {
  std::vector<std::vector<std::string>> out;
  for (const char* t : {"pipeline", "videos", "clips", "stage_runs", "measurements", "verdicts",
                        "reviews", "artifacts", "detections", "events", "shards", "shard_clips"}) {
    out.push_back(QueryRows(db, std::string("SELECT * FROM ") + t + " ORDER BY rowid"));
  }
  return out;
}

class ShardTest : public ::testing::Test {
 protected:
  void SetUp() override {
    pool_ = (dir_ / "pool").string();
    const auto r = RunDoasido({"synth", "--out", pool_, "--clips", "10", "--frames", "30",
                               "--width", "96", "--height", "72", "--seed", "11", "--no-bundles",
                               "--mix", "clean=0.5,static=0.2,cut=0.1,pan=0.2"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  // A database in its own folder with the pool ingested.
  std::filesystem::path Ingested(const std::string& name) {
    const auto db = dir_ / name / "doasido.db";
    std::filesystem::create_directories(db.parent_path());
    EXPECT_EQ(RunDoasido({"init", "--db", db.string(), "--pipeline", "filters"}).exit_code, 0);
    const auto r = RunDoasido({"ingest", "--db", db.string(), pool_ + "/Annotations"});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return db;
  }
  void Run(const std::filesystem::path& db, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"run", "--db", db.string(), "--jobs", "1"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = RunDoasido(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  std::vector<std::filesystem::path> Shard(const std::filesystem::path& db, int n,
                                           std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"shard", "--db", db.string(), "--shards",
                                     std::to_string(n), "--out", (db.parent_path() / "sh").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = RunDoasido(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::vector<std::filesystem::path> out;
    for (const auto& row : QueryRows(db, "SELECT name FROM shards ORDER BY id")) {
      out.push_back(db.parent_path() / "sh" / row / "doasido.db");
    }
    return out;
  }
  testing::CommandResult Merge(const std::filesystem::path& db,
                               const std::vector<std::filesystem::path>& shards) {
    std::vector<std::string> args = {"merge", "--db", db.string()};
    for (const auto& s : shards) args.push_back(s.string());
    return RunDoasido(args);
  }

  TempDir dir_;
  std::string pool_;
};

TEST_F(ShardTest, ShardedRunEqualsOneMachineAndMergingTwiceChangesNothing) {
  const auto single = Ingested("single");
  Run(single);
  const auto parent = Ingested("parent");
  const auto shards = Shard(parent, 3);
  ASSERT_EQ(shards.size(), 3u);
  // All clips of a video in one shard; every clip in exactly one.
  EXPECT_EQ(QueryRows(parent, "SELECT COUNT(*) FROM shard_clips")[0], "10");
  EXPECT_TRUE(QueryRows(parent, "SELECT c.video_id FROM clips c JOIN shard_clips s ON"
                                " s.clip_id = c.id GROUP BY c.video_id"
                                " HAVING COUNT(DISTINCT s.shard_id) > 1").empty());
  // The parent's own workers leave sharded clips alone.
  Run(parent);
  EXPECT_EQ(QueryRows(parent, "SELECT COUNT(*) FROM stage_runs WHERE state = 'done'")[0], "0");
  // Sharding again finds nothing: those clips are out already.
  EXPECT_NE(RunDoasido({"shard", "--db", parent.string(), "--shards", "2"}).exit_code, 0);

  for (const auto& s : shards) Run(s);
  const auto merged = Merge(parent, shards);
  ASSERT_EQ(merged.exit_code, 0) << merged.err;
  EXPECT_EQ(ResultTables(parent), ResultTables(single));
  // Artifacts came back with their rows.
  for (const auto& path : QueryRows(parent, "SELECT path FROM artifacts")) {
    EXPECT_TRUE(std::filesystem::exists(parent.parent_path() / "artifacts" / path)) << path;
  }
  const auto once = AllRows(parent);
  ASSERT_EQ(Merge(parent, shards).exit_code, 0);
  EXPECT_EQ(AllRows(parent), once);
  const auto status = RunDoasido({"status", "--db", parent.string()});
  EXPECT_NE(status.out.find("shard-002"), std::string::npos) << status.out;
}

// Two databases made in one folder before either runs: each decided and
// claimed its artifact root at creation, so the second made runs, shards
// and merges first and the first made after it, and each ends with what one
// machine's run gives (issue 53: the second used to be locked out of every
// command by foreign_artifacts).
TEST_F(ShardTest, TwoDatabasesMadeInOneFolderBeforeEitherRunsBothRunShardAndMerge) {
  const auto single = Ingested("single");
  Run(single);
  const auto folder = dir_ / "both";
  std::filesystem::create_directories(folder);
  const auto a = folder / "a.db", b = folder / "b.db";
  for (const auto& db : {a, b}) {
    ASSERT_EQ(RunDoasido({"init", "--db", db.string(), "--pipeline", "filters"}).exit_code, 0);
  }
  EXPECT_EQ(QueryRows(a, "SELECT value FROM meta WHERE key = 'artifact_root'"),
            std::vector<std::string>{"artifacts"});
  EXPECT_EQ(QueryRows(b, "SELECT value FROM meta WHERE key = 'artifact_root'"),
            std::vector<std::string>{"b.artifacts"});
  for (const auto& db : {b, a}) {  // the one made second goes first
    const std::string name = db.stem().string();
    ASSERT_EQ(RunDoasido({"ingest", "--db", db.string(), pool_ + "/Annotations"}).exit_code, 0);
    ASSERT_EQ(RunDoasido({"status", "--db", db.string()}).exit_code, 0);
    const auto shard = RunDoasido({"shard", "--db", db.string(), "--shards", "2", "--out",
                                   (folder / (name + "-shards")).string()});
    ASSERT_EQ(shard.exit_code, 0) << shard.err;
    std::vector<std::filesystem::path> shards;
    for (const auto& row : QueryRows(db, "SELECT name FROM shards ORDER BY id")) {
      shards.push_back(folder / (name + "-shards") / row / "doasido.db");
    }
    ASSERT_EQ(shards.size(), 2u);
    for (const auto& s : shards) Run(s);
    const auto merged = Merge(db, shards);
    ASSERT_EQ(merged.exit_code, 0) << merged.err;
    EXPECT_EQ(ResultTables(db), ResultTables(single)) << db;
  }
  for (const auto& [db, root] : {std::pair{a, "artifacts"}, std::pair{b, "b.artifacts"}}) {
    for (const auto& path : QueryRows(db, "SELECT path FROM artifacts")) {
      EXPECT_TRUE(std::filesystem::exists(folder / root / path)) << path;
    }
    // Each root is its own database's (its owner file names the uuid).
    const std::string owner = testing::ReadFile(folder / root / ".doasido-database");
    EXPECT_NE(owner.find(QueryRows(db, "SELECT value FROM meta WHERE key = 'uuid'").at(0)),
              std::string::npos) << owner;
    // Work on each afterwards, in the other order too: nothing locks it out.
    const auto status = RunDoasido({"status", "--db", db.string()});
    EXPECT_EQ(status.exit_code, 0) << status.err;
  }
}

TEST_F(ShardTest, APartlyDoneShardMergesItsDonePart) {
  const auto parent = Ingested("parent");
  const auto shards = Shard(parent, 1);
  ASSERT_EQ(shards.size(), 1u);
  {  // A worker on the first stages alone, stopped once every probe run is done.
    const std::string command = "exec '" + testing::DoasidoBin().string() + "' worker --db '" +
                                shards[0].string() + "' --stages download,probe --poll 0.05";
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    for (int i = 0; i < 1200; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (QueryRows(shards[0], "SELECT COUNT(*) FROM stage_runs WHERE stage = 'probe'"
                               " AND state = 'done'")[0] == "10") {
        break;
      }
    }
    kill(pid, SIGTERM);
    waitpid(pid, nullptr, 0);
  }
  ASSERT_EQ(Merge(parent, shards).exit_code, 0);
  EXPECT_EQ(QueryRows(parent, "SELECT COUNT(*) FROM stage_runs WHERE stage = 'probe'"
                              " AND state = 'done'")[0], "10");
  EXPECT_EQ(QueryRows(parent, "SELECT COUNT(*) FROM stage_runs WHERE stage = 'filters_analyze'"
                              " AND state = 'pending'")[0],
            QueryRows(parent, "SELECT COUNT(*) FROM stage_runs WHERE stage = 'probe'"
                              " AND verdict = 'pass'")[0]);
  // The rest is finished in the shard and merged again.
  Run(shards[0]);
  ASSERT_EQ(Merge(parent, shards).exit_code, 0);
  EXPECT_EQ(QueryRows(parent, "SELECT COUNT(*) FROM stage_runs WHERE state IN "
                              "('pending', 'running')")[0], "0");
}

TEST_F(ShardTest, RefusesAForeignShardAndOneRunWithOtherParameters) {
  const auto parent = Ingested("parent");
  const auto other = Ingested("other");
  const auto mine = Shard(parent, 1);
  const auto theirs = Shard(other, 1);
  const auto before = AllRows(parent);
  const auto foreign = Merge(parent, theirs);
  EXPECT_EQ(foreign.exit_code, 1);
  EXPECT_NE(foreign.err.find("foreign_shard"), std::string::npos) << foreign.err;
  EXPECT_NE(foreign.err.find(theirs[0].string()), std::string::npos) << foreign.err;
  EXPECT_EQ(AllRows(parent), before);

  testing::WriteFile(dir_ / "other.toml", "[activity]\nmin_active_fraction = 0.5\n");
  Run(mine[0], {"--config", (dir_ / "other.toml").string()});
  const auto mismatch = Merge(parent, mine);
  EXPECT_EQ(mismatch.exit_code, 1);
  EXPECT_NE(mismatch.err.find("config_mismatch"), std::string::npos) << mismatch.err;
  EXPECT_NE(mismatch.err.find("activity"), std::string::npos) << mismatch.err;
  EXPECT_EQ(AllRows(parent), before);
}

}  // namespace
}  // namespace doasido
