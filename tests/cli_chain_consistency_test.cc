// The chain stays consistent when anything changes (issue #42), through the
// built binary on synthetic clips with their ground-truth bundles:
//  - a changed recon parameter re-runs recon and everything after it for
//    exactly the clips it had run on, `dataset create` in between is refused
//    naming them, and the version cut afterwards holds only trajectories
//    retargeted from the new reconstructions, each naming its upstream runs;
//  - a failed re-run carries no verdict and is no success;
//  - `--allow-stale` cuts a version anyway and records it;
//  - an export refuses a version whose episodes disagree on the robot;
//  - error text is bounded in bytes, the whole log named;
//  - a merged shard hands its clips back and refuses further runs;
//  - worker options are range-checked before anything runs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <set>

#include "core/config.h"
#include "dataset/version.h"
#include "testing/db_dump.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;
using testing::QueryRows;
using testing::ReadFile;
using testing::RunDoasido;
using testing::TempDir;
using testing::WriteFile;

constexpr const char* kPipeline = "download,probe,bundle,recon,retarget_kinematic";
// The stand-in model: copies the synthetic bundle of the clip's video.
constexpr const char* kBundleCommand =
    "[bundle]\ncommand = \"cp -r $(dirname $(dirname {video}))/bundles/$(basename {video} "
    ".mp4)/. {output}/\"\n";

std::int64_t Count(const fs::path& db, const std::string& sql) {
  return std::stoll(QueryRows(db, sql).at(0));
}

// Five clean clips run through the pipeline once; each test works on a copy.
class ChainTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    pool_ = new TempDir();
    const fs::path synth = *pool_ / "s";
    ASSERT_EQ(
        RunDoasido({"synth", "--out", synth.string(), "--clips", "5", "--seed", "11", "--frames",
                    "30", "--width", "160", "--height", "120", "--mix", "clean=1"})
            .exit_code,
        0);
    WriteFile(*pool_ / "run.toml", kBundleCommand);
    ASSERT_EQ(
        RunDoasido({"init", "--db", (*pool_ / "d.db").string(), "--pipeline", kPipeline}).exit_code,
        0);
    const auto run =
        RunDoasido({"run", "--db", (*pool_ / "d.db").string(), "--jobs", "2", "--config",
                    (*pool_ / "run.toml").string(), (synth / "clips.csv").string()});
    ASSERT_EQ(run.exit_code, 0) << run.err;
  }
  static void TearDownTestSuite() {
    delete pool_;
    pool_ = nullptr;
  }
  void SetUp() override {
    fs::copy_file(*pool_ / "d.db", work_ / "d.db");
    fs::copy(*pool_ / "artifacts", work_ / "artifacts", fs::copy_options::recursive);
    fs::create_directory_symlink(*pool_ / "s", work_ / "s");
    WriteFile(work_ / "run.toml", kBundleCommand);
  }
  std::string Db() const { return (work_ / "d.db").string(); }
  std::string Config(const std::string& extra) const {
    const fs::path path = work_ / "changed.toml";
    WriteFile(path, std::string(kBundleCommand) + extra);
    return path.string();
  }

  static TempDir* pool_;
  TempDir work_;
};
TempDir* ChainTest::pool_ = nullptr;

TEST_F(ChainTest, ChangedReconReRunsDownstreamAndVersionsWaitForIt) {
  const fs::path db = Db();
  ASSERT_EQ(Count(db,
                  "SELECT COUNT(*) FROM stage_runs WHERE stage = 'retarget_kinematic'"
                  " AND state = 'done'"),
            5);
  const auto old_recon = QueryRows(db,
                                   "SELECT clip_id, param_hash, finished_at FROM stage_runs"
                                   " WHERE stage = 'recon' ORDER BY clip_id");
  // Recon alone under the new parameters: its later runs wait for it.
  const std::string changed = Config("[recon.gravity]\nuse_bundle_up = false\n");
  const auto recon = RunDoasido({"run", "--db", Db(), "--config", changed, "--stages", "recon"});
  ASSERT_EQ(recon.exit_code, 0) << recon.err;
  EXPECT_NE(recon.out.find("recon: parameters changed, 5 clips queued again, and 5 later runs"),
            std::string::npos)
      << recon.out;
  const auto new_recon = QueryRows(db,
                                   "SELECT clip_id, param_hash, finished_at FROM stage_runs"
                                   " WHERE stage = 'recon' AND state = 'done' ORDER BY clip_id");
  ASSERT_EQ(new_recon.size(), 5u);
  for (size_t i = 0; i < 5; ++i) EXPECT_NE(new_recon[i], old_recon[i]);
  const std::string new_hash = QueryRows(db,
                                         "SELECT DISTINCT param_hash FROM stage_runs"
                                         " WHERE stage = 'recon'")
                                   .at(0);
  EXPECT_EQ(QueryRows(db,
                      "SELECT clip_id, state, IFNULL(verdict, '~'), requeued_by FROM"
                      " stage_runs WHERE stage = 'retarget_kinematic' ORDER BY clip_id"),
            (std::vector<std::string>{"1|pending|~|recon", "2|pending|~|recon", "3|pending|~|recon",
                                      "4|pending|~|recon", "5|pending|~|recon"}));
  const auto status = RunDoasido({"status", "--db", Db()});
  EXPECT_NE(status.out.find("5 runs queued again because their recon run changed"),
            std::string::npos)
      << status.out;

  // A version now would mix reconstructions with trajectories of the old ones.
  const fs::path root = work_ / "datasets";
  const auto refused = RunDoasido({"dataset", "create", "--db", Db(), "--root", root.string(),
                                   "--select", "all", "--no-thumbnails"});
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("unsettled_runs"), std::string::npos) << refused.err;
  for (int clip = 1; clip <= 5; ++clip) {
    EXPECT_NE(refused.err.find("clip " + std::to_string(clip) + " "), std::string::npos)
        << refused.err;
  }
  EXPECT_NE(refused.err.find("retarget_kinematic pending (queued again after recon changed)"),
            std::string::npos)
      << refused.err;
  EXPECT_FALSE(fs::exists(root / "default/v1"));

  const auto rest = RunDoasido({"run", "--db", Db(), "--config", changed});
  ASSERT_EQ(rest.exit_code, 0) << rest.err;
  // Exactly recon and what follows ran again, once each, for the five clips.
  for (const auto& row : QueryRows(db,
                                   "SELECT stage, clip_id, COUNT(*) FROM events WHERE"
                                   " kind = 'done' GROUP BY 1, 2")) {
    const bool again = row.rfind("recon|", 0) == 0 || row.rfind("retarget_kinematic|", 0) == 0;
    EXPECT_EQ(row.substr(row.rfind('|') + 1), again ? "2" : "1") << row;
  }
  EXPECT_EQ(Count(db, "SELECT COUNT(*) FROM stage_runs WHERE state != 'done'"), 0);

  const auto made = RunDoasido({"dataset", "create", "--db", Db(), "--root", root.string(),
                                "--select", "all", "--no-thumbnails"});
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const dataset::Manifest m = dataset::ReadManifest(root / "default/v1");
  EXPECT_FALSE(m.allow_stale);
  ASSERT_FALSE(m.episodes.empty());
  std::map<std::int64_t, std::string> recon_finished;
  for (const auto& row : new_recon) {
    const auto bar = row.find('|');
    recon_finished[std::stoll(row.substr(0, bar))] = row.substr(row.rfind('|') + 1);
  }
  for (const dataset::Episode& e : m.episodes) {
    ASSERT_TRUE(e.upstream.is_array()) << e.id;
    std::set<std::string> stages;
    for (const Json& input : e.upstream) {
      stages.insert(input.at("stage").get<std::string>());
      if (input.at("stage") != "recon") continue;
      EXPECT_EQ(input.at("param_hash"), new_hash) << e.id;
      // The very run that is the clip's recon now (SQLite prints REAL with 15 digits).
      EXPECT_NEAR(input.at("finished_at").get<double>(), std::stod(recon_finished[e.clip_id]), 1e-3)
          << e.id;
      EXPECT_FALSE(input.at("artifacts").empty()) << e.id;
    }
    EXPECT_EQ(stages, (std::set<std::string>{"download", "probe", "bundle", "recon"})) << e.id;
    for (const dataset::StageProvenance& s : e.stages) {
      if (s.stage == "recon") {
        EXPECT_EQ(s.param_hash, new_hash) << e.id;
      }
      EXPECT_TRUE(s.finished_at.has_value()) << e.id << " " << s.stage;
    }
    // The trajectory in the version is the one retargeted after the new recon.
    const Json info = Json::parse(
        ReadFile(root / "default/v1/episodes" / e.id / "recon" / "reconstruction.json"));
    EXPECT_NE(info.dump().find("support_plane"), std::string::npos) << info.dump();
  }
}

TEST_F(ChainTest, AFailedReRunHasNoVerdictAndIsNoSuccess) {
  const fs::path db = Db();
  // Another (valid) hand re-queues retarget_kinematic; with the bundles and
  // reconstructions it reads gone, the re-runs fail (a hand name that does
  // not exist is refused when the config loads, before any run).
  const std::string changed = Config("[retarget_kinematic]\nhand = \"allegro\"\n");
  for (const auto& clip : fs::directory_iterator(work_ / "artifacts")) {
    if (!clip.is_directory()) continue;
    fs::remove_all(clip.path() / "bundle");
    fs::remove_all(clip.path() / "recon");
  }
  const auto run = RunDoasido({"run", "--db", Db(), "--config", changed, "--max-attempts", "1",
                               "--stages", "retarget_kinematic"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // The re-runs fail; a failed run keeps neither the verdict nor the
  // parameters of its earlier success.
  EXPECT_GE(Count(db,
                  "SELECT COUNT(*) FROM stage_runs WHERE stage = 'retarget_kinematic'"
                  " AND state = 'failed'"),
            1);
  EXPECT_EQ(Count(db,
                  "SELECT COUNT(*) FROM stage_runs WHERE state != 'done' AND"
                  " (verdict IS NOT NULL OR param_hash IS NOT NULL)"),
            0);
  EXPECT_EQ(Count(db,
                  "SELECT COUNT(*) FROM stage_runs WHERE stage = 'retarget_kinematic'"
                  " AND verdict = 'pass'"),
            0);
  // Failed is settled (nothing will run it), but no success: no episode.
  const auto made = RunDoasido({"dataset", "create", "--db", Db(), "--root",
                                (work_ / "ds").string(), "--select", "success"});
  EXPECT_EQ(made.exit_code, 1);
  EXPECT_NE(made.err.find("empty_version"), std::string::npos) << made.err;
}

TEST_F(ChainTest, AllowStaleCutsTheVersionAndRecordsIt) {
  const std::string changed = Config("[recon.gravity]\nuse_bundle_up = false\n");
  ASSERT_EQ(RunDoasido({"run", "--db", Db(), "--config", changed, "--stages", "recon"}).exit_code,
            0);
  const fs::path root = work_ / "datasets";
  const auto made =
      RunDoasido({"dataset", "create", "--db", Db(), "--root", root.string(), "--select", "all",
                  "--no-thumbnails", "--allow-empty", "--allow-stale"});
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const dataset::Manifest m = dataset::ReadManifest(root / "default/v1");
  EXPECT_TRUE(m.allow_stale);
  EXPECT_EQ(m.stale.size(), 5u);
  EXPECT_TRUE(m.episodes.empty()) << "pending trajectories have no verdict to select";
}

TEST_F(ChainTest, ExportsRefuseAVersionMixingRobots) {
  const fs::path root = work_ / "datasets";
  ASSERT_EQ(RunDoasido({"dataset", "create", "--db", Db(), "--root", root.string(), "--select",
                        "all", "--no-thumbnails"})
                .exit_code,
            0);
  const dataset::Manifest m = dataset::ReadManifest(root / "default/v1");
  ASSERT_GE(m.episodes.size(), 2u);
  // The second episode's trajectory claims another robot.
  const fs::path second = root / "default/v1/episodes" / m.episodes[1].id / "trajectory.json";
  Json t = Json::parse(ReadFile(second));
  t["embodiment"] = "allegro";
  fs::remove(second);  // a hard link into the artifacts: do not write through it
  WriteFile(second, t.dump());
  for (const char* format : {"robomimic", "lerobot"}) {
    const fs::path out = work_ / (std::string("out.") + format);
    const auto r = RunDoasido({"dataset", "export", "--root", root.string(), "v1", "--format",
                               format, "--out", out.string(), "--no-videos", "--no-verify"});
    EXPECT_EQ(r.exit_code, 1) << format;
    EXPECT_NE(r.err.find("mixed_trajectories"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("embodiment"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(m.episodes[1].external_id), std::string::npos) << r.err;
    if (std::string(format) == "robomimic") {
      EXPECT_FALSE(fs::exists(out)) << format;
    }
  }
}

TEST(BoundedText, A9MegabyteErrorLineIsStoredAsItsTailAndTheWholeLogIsNamed) {
  TempDir dir;
  const fs::path synth = dir / "s";
  ASSERT_EQ(RunDoasido({"synth", "--out", synth.string(), "--clips", "2", "--seed", "2", "--frames",
                        "24", "--width", "96", "--height", "72", "--mix", "clean=1",
                        "--no-annotations", "--no-bundles"})
                .exit_code,
            0);
  WriteFile(dir / "loud.toml",
            "[bundle]\ncommand = \"head -c 9000000 /dev/zero | tr -c x x; echo; echo the real "
            "reason; exit 1\"\n");
  const fs::path db = dir / "d.db";
  ASSERT_EQ(
      RunDoasido({"init", "--db", db.string(), "--pipeline", "download,probe,bundle"}).exit_code,
      0);
  const auto run = RunDoasido({"run", "--db", db.string(), "--config", (dir / "loud.toml").string(),
                               (synth / "clips.csv").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ASSERT_EQ(
      Count(db, "SELECT COUNT(*) FROM stage_runs WHERE stage = 'bundle' AND state = 'failed'"), 2);
  EXPECT_LE(Count(db, "SELECT MAX(LENGTH(CAST(error AS BLOB))) FROM stage_runs"), 8192);
  EXPECT_LE(Count(db, "SELECT MAX(LENGTH(CAST(detail AS BLOB))) FROM events"), 8192);
  for (const auto& error : QueryRows(db, "SELECT error FROM stage_runs WHERE state = 'failed'")) {
    EXPECT_NE(error.find("the real reason"), std::string::npos) << error.substr(0, 300);
    EXPECT_NE(error.find("command.log"), std::string::npos) << error.substr(0, 300);
  }
  // The failed run's folder is gone (it is no output), its log is kept.
  EXPECT_FALSE(fs::exists(dir / "artifacts/1/bundle"));
  std::uintmax_t largest = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir / "logs/1")) {
    if (e.path().filename() == "command.log") largest = std::max(largest, fs::file_size(e.path()));
  }
  EXPECT_GE(largest, 9000000u);
  // Three attempts of two clips: still a small database and a short listing.
  EXPECT_LT(fs::file_size(db), 2000000u);
  const auto list = RunDoasido({"queue", "list", "--db", db.string()});
  EXPECT_LT(list.out.size(), 100000u);
}

TEST(MergedShard, HandsItsClipsBackAndRefusesNewRuns) {
  TempDir dir;
  const fs::path synth = dir / "s";
  ASSERT_EQ(RunDoasido({"synth", "--out", synth.string(), "--clips", "2", "--seed", "5", "--frames",
                        "24", "--width", "96", "--height", "72", "--no-bundles"})
                .exit_code,
            0);
  const fs::path parent = dir / "p/d.db";
  fs::create_directories(parent.parent_path());
  ASSERT_EQ(RunDoasido({"init", "--db", parent.string(), "--pipeline", "download,probe"}).exit_code,
            0);
  ASSERT_EQ(
      RunDoasido({"ingest", "--db", parent.string(), (synth / "clips.csv").string()}).exit_code, 0);
  ASSERT_EQ(RunDoasido({"shard", "--db", parent.string(), "--shards", "1"}).exit_code, 0);
  const fs::path shard = parent.parent_path() / "shards/shard-000/doasido.db";
  ASSERT_TRUE(fs::exists(shard));
  ASSERT_EQ(RunDoasido({"run", "--db", shard.string()}).exit_code, 0);
  const auto merged = RunDoasido({"merge", "--db", parent.string(), shard.string()});
  ASSERT_EQ(merged.exit_code, 0) << merged.err;
  EXPECT_NE(merged.out.find("its 2 clips are this database's again"), std::string::npos)
      << merged.out;
  EXPECT_EQ(Count(parent, "SELECT COUNT(*) FROM shard_clips"), 0);

  // The merged shard takes no more runs, and says whose the clips are.
  const auto again =
      RunDoasido({"queue", "reset", "--db", shard.string(), "--stage", "probe", "--all"});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  const auto refused = RunDoasido({"run", "--db", shard.string()});
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("merged_shard"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find(parent.string()), std::string::npos) << refused.err;

  // The parent re-queues and runs a clip of the shard as any of its own.
  ASSERT_EQ(
      RunDoasido({"queue", "reset", "--db", parent.string(), "--stage", "probe", "--clip", "1"})
          .exit_code,
      0);
  const auto run = RunDoasido({"run", "--db", parent.string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(Count(parent, "SELECT COUNT(*) FROM stage_runs WHERE state IN ('pending', 'running')"),
            0);
  EXPECT_EQ(Count(parent,
                  "SELECT COUNT(*) FROM events WHERE kind = 'done' AND stage = 'probe'"
                  " AND clip_id = 1"),
            2);
  // A second merge of the old shard changes nothing the parent re-did.
  const auto before =
      QueryRows(parent, "SELECT clip_id, stage, state, finished_at FROM stage_runs");
  ASSERT_EQ(RunDoasido({"merge", "--db", parent.string(), shard.string()}).exit_code, 0);
  EXPECT_EQ(QueryRows(parent, "SELECT clip_id, stage, state, finished_at FROM stage_runs"), before);
}

TEST(WorkerOptions, OutOfRangeValuesAreRefusedBeforeAnyWork) {
  TempDir dir;
  const fs::path db = dir / "d.db";
  ASSERT_EQ(RunDoasido({"init", "--db", db.string(), "--pipeline", "download,probe"}).exit_code, 0);
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--jobs", "-5"},        {"--jobs", "0"},    {"--jobs", "100000"}, {"--lease", "0"},
      {"--lease", "-1"},       {"--lease", "nan"}, {"--lease", "inf"},   {"--lease", "0.5"},
      {"--max-attempts", "0"}, {"--poll", "nan"}};
  for (const auto& [option, value] : bad) {
    for (const char* command : {"run", "worker"}) {
      const auto r = RunDoasido({command, "--db", db.string(), option, value});
      EXPECT_NE(r.exit_code, 0) << command << " " << option << " " << value;
      EXPECT_NE(r.err.find(option), std::string::npos) << r.err;
      EXPECT_NE(r.err.find(value), std::string::npos) << r.err;
    }
  }
  EXPECT_EQ(Count(db, "SELECT COUNT(*) FROM events WHERE kind = 'claim'"), 0);
  EXPECT_EQ(RunDoasido({"status", "--db", db.string()}).exit_code, 0);
}

}  // namespace
}  // namespace doasido

namespace doasido {
namespace {

// Issue #50, finding 2: between a merge's commit and the end of its folder
// moves (slowed here to 0.3 s a folder) `deploy plan` and `dataset create`
// saw the merged rows without their folders (`no_trajectory`,
// `empty_version`). They now wait for the placement and see the new state.
TEST(MergePlacement, ReadersNeverSeeRowsWithoutTheirFolders) {
  TempDir dir;
  const fs::path synth = dir / "s";
  ASSERT_EQ(RunDoasido({"synth", "--out", synth.string(), "--clips", "3", "--seed", "7",
                        "--frames", "24", "--width", "160", "--height", "120", "--mix", "clean=1"})
                .exit_code,
            0);
  WriteFile(dir / "run.toml", kBundleCommand);
  const fs::path parent = dir / "p/d.db";
  fs::create_directories(parent.parent_path());
  ASSERT_EQ(RunDoasido({"init", "--db", parent.string(), "--pipeline", kPipeline}).exit_code, 0);
  ASSERT_EQ(RunDoasido({"ingest", "--db", parent.string(), (synth / "clips.csv").string()})
                .exit_code,
            0);
  ASSERT_EQ(RunDoasido({"shard", "--db", parent.string(), "--shards", "1", "--config",
                        (dir / "run.toml").string()})
                .exit_code,
            0);
  const fs::path shard = parent.parent_path() / "shards/shard-000/doasido.db";
  const auto ran =
      RunDoasido({"run", "--db", shard.string(), "--config", (dir / "run.toml").string()});
  ASSERT_EQ(ran.exit_code, 0) << ran.err;
  const std::string done_sql =
      "SELECT clip_id FROM stage_runs WHERE stage = 'retarget_kinematic' AND state = 'done'"
      " AND verdict = 'pass' ORDER BY clip_id";
  const auto passed = QueryRows(shard, done_sql);
  ASSERT_GE(passed.size(), 2u);

  setenv("DOASIDO_TEST_PAUSE", "merge_placement=300", 1);
  const int merge = testing::Spawn(
      {testing::DoasidoBin().string(), "merge", "--db", parent.string(), shard.string()},
      dir / "merge.log");
  unsetenv("DOASIDO_TEST_PAUSE");
  // Wait for the merge's commit (its journal), then read at once.
  bool committed = false;
  for (int i = 0; i < 600 && !committed; ++i) {
    committed = QueryRows(parent, "SELECT COUNT(*) FROM meta WHERE key = 'pending_placement'")
                    .at(0) == "1";
    if (!committed) usleep(10000);
  }
  ASSERT_TRUE(committed) << ReadFile(dir / "merge.log");
  const auto plan = RunDoasido({"deploy", "plan", "--db", parent.string(), "--clip",
                                passed.back(), "--no-replay", "--yaw-steps", "1",
                                "--offset-steps", "1", "--out", (dir / "plan.json").string()});
  const auto made = RunDoasido({"dataset", "create", "--db", parent.string(), "--root",
                                (dir / "datasets").string(), "--select", "all",
                                "--no-thumbnails"});
  EXPECT_EQ(testing::WaitFor(merge), 0) << ReadFile(dir / "merge.log");
  // The plan found the merged run's trajectory (whether the synthetic
  // trajectory passes the arm's checks is another matter: exit 0 or
  // plan_failed_checks, with the plan written either way).
  EXPECT_THAT(plan.err, ::testing::HasSubstr("planning retarget_kinematic run"));
  EXPECT_THAT(plan.err, ::testing::Not(::testing::HasSubstr("no_trajectory")));
  EXPECT_TRUE(plan.exit_code == 0 || plan.err.find("plan_failed_checks") != std::string::npos)
      << plan.err;
  EXPECT_TRUE(fs::exists(dir / "plan.json"));
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const dataset::Manifest m = dataset::ReadManifest(dir / "datasets/default/v1");
  EXPECT_EQ(m.episodes.size(), passed.size()) << made.out << made.err;
  // Every merged row has its folder.
  for (const auto& path : QueryRows(parent, "SELECT path FROM artifacts")) {
    EXPECT_TRUE(fs::exists(parent.parent_path() / "artifacts" / path)) << path;
  }
}

}  // namespace
}  // namespace doasido
