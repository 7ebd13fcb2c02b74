// Artifacts belong to the run that wrote them, versions prove what they
// hold, exports are whole or absent (issue #36), each finding tried through
// the built binary and checked in the database and the files afterwards:
// 1. two databases in one folder keep their own artifact roots; a root
//    another database owns is refused by name;
// 2. reset and failed runs leave no folder or row a later command takes;
// 3. merge copies (the parent never shares a file with the shard) and holds
//    back, by name, a clip whose recorded file is missing;
// 4. a person's verification counts only for the trajectory they saw;
// 5. an edited manifest fails verify and show, list names a broken version
//    and keeps the healthy ones, a stray vK folder is named and skipped,
//    export verifies first;
// 6. exports killed with SIGKILL leave the old export or the new one whole;
// 7. a misspelt hand is refused at load, self-merge and non-databases are
//    refused naming the right file, measurements hold relative paths, and no
//    stage leaves an empty folder.
#include <csignal>
#include <fstream>
#include <random>
#include <set>
#include <thread>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "dataset/version.h"
#include "db/database.h"
#include "ingest/file_sha256.h"
#include "stages/kinematic_stage.h"
#include "testing/db_dump.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;
using doasido::testing::QueryRows;
using doasido::testing::ReadFile;
using doasido::testing::RunDoasido;
using doasido::testing::TempDir;
using doasido::testing::WriteFile;

constexpr const char* kPipeline =
    "download,probe,filters_analyze,shot_boundary,interaction,out_of_frame,activity,"
    "camera_motion,bundle,recon,retarget_kinematic";
constexpr const char* kTrajectoryStage = "retarget_kinematic";

bool Has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// One small pool run through the whole pipeline once; each test works on
// its own copy (the database and its artifact folder).
class CliArtifacts : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    pool_ = new TempDir();
    const fs::path synth = *pool_ / "s";
    testing::SynthPool(synth, 3, 5, 30, 160, 120, "clean=1");
    WriteFile(*pool_ / "run.toml", BundleConfig());
    const auto base = *pool_ / "base" / "d.db";
    fs::create_directories(base.parent_path());
    ASSERT_EQ(RunDoasido({"init", "--db", base.string(), "--pipeline", kPipeline}).exit_code, 0);
    const auto run = RunDoasido({"run", "--db", base.string(), "--jobs", "2", "--config",
                                 (*pool_ / "run.toml").string(), synth.string()});
    ASSERT_EQ(run.exit_code, 0) << run.err;
  }
  static void TearDownTestSuite() {
    delete pool_;
    pool_ = nullptr;
  }
  static std::string BundleConfig() { return testing::SyntheticBundleConfig(); }
  // A copy of the finished database (with its artifacts) in `dir`.
  fs::path CopyBase(const fs::path& dir) {
    fs::create_directories(dir);
    fs::copy_file(*pool_ / "base" / "d.db", dir / "d.db");
    fs::copy(*pool_ / "base" / "artifacts", dir / "artifacts", fs::copy_options::recursive);
    fs::create_directory_symlink(*pool_ / "s", dir / "s");
    return dir / "d.db";
  }
  static std::vector<std::string> DoneTrajectoryClips(const fs::path& db) {
    return QueryRows(db, std::string("SELECT clip_id FROM stage_runs WHERE stage = '") +
                             kTrajectoryStage + "' AND state = 'done' AND verdict = 'pass'"
                             " ORDER BY clip_id");
  }
  static TempDir* pool_;
  TempDir work_;
};
TempDir* CliArtifacts::pool_ = nullptr;

// Finding 1.
TEST_F(CliArtifacts, TwoDatabasesInOneFolderKeepTheirOwnArtifacts) {
  const fs::path a = CopyBase(work_ / "w");
  const auto clips = DoneTrajectoryClips(a);
  ASSERT_FALSE(clips.empty());
  const fs::path a_trajectory = work_ / "w/artifacts" / clips[0] / kTrajectoryStage / "trajectory.json";
  const std::string a_sha = ingest::FileSha256(a_trajectory);
  // A second database beside it, whose bundle model fails on every clip.
  const fs::path b = work_ / "w" / "b.db";
  ASSERT_EQ(RunDoasido({"init", "--db", b.string(), "--pipeline", kPipeline}).exit_code, 0);
  WriteFile(work_ / "fail.toml", "[bundle]\ncommand = \"false\"\n");
  RunDoasido({"run", "--db", b.string(), "--config", (work_ / "fail.toml").string(),
              (work_ / "w/s").string()});
  EXPECT_EQ(QueryRows(b, "SELECT value FROM meta WHERE key = 'artifact_root'"),
            std::vector<std::string>{"b.artifacts"});
  EXPECT_EQ(QueryRows(a, "SELECT value FROM meta WHERE key = 'artifact_root'"),
            std::vector<std::string>{"artifacts"});
  EXPECT_EQ(ingest::FileSha256(a_trajectory), a_sha);  // a's files untouched
  EXPECT_FALSE(fs::exists(work_ / "w/b.artifacts" / clips[0] / kTrajectoryStage));
  // b's own run did not get there: nothing to plan, and it says which run.
  const auto plan = RunDoasido({"deploy", "plan", "--db", b.string(), "--clip", clips[0], "--out",
                                (work_ / "plan.json").string()});
  EXPECT_NE(plan.exit_code, 0);
  EXPECT_TRUE(Has(plan.err, "none recorded")) << plan.err;
  EXPECT_FALSE(fs::exists(work_ / "plan.json"));
  // a's plan names a's run.
  const auto a_plan = RunDoasido({"deploy", "plan", "--db", a.string(), "--clip", clips[0],
                                  "--out", (work_ / "a_plan.json").string()});
  EXPECT_EQ(a_plan.exit_code, 0) << a_plan.err;
  EXPECT_TRUE(Has(a_plan.err, "retarget_kinematic run")) << a_plan.err;
  // Pointing b at a's folder is refused by name.
  {
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(b.c_str(), &raw), SQLITE_OK);
    EXPECT_EQ(sqlite3_exec(raw, "UPDATE meta SET value = 'artifacts' WHERE key = 'artifact_root'",
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(raw);
  }
  const auto status = RunDoasido({"status", "--db", b.string()});
  EXPECT_NE(status.exit_code, 0);
  EXPECT_TRUE(Has(status.err, "foreign_artifacts")) << status.err;
  EXPECT_TRUE(Has(status.err, a.string())) << status.err;
}

// Findings 2 and 7 (a hand that does not exist).
TEST_F(CliArtifacts, ResetAndFailedRunsLeaveNothingToTake) {
  const fs::path db = CopyBase(work_ / "w");
  const auto clips = DoneTrajectoryClips(db);
  ASSERT_FALSE(clips.empty());
  const fs::path folder = work_ / "w/artifacts" / clips[0] / kTrajectoryStage;
  ASSERT_TRUE(fs::exists(folder / "trajectory.json"));
  ASSERT_EQ(RunDoasido({"queue", "reset", "--db", db.string(), "--stage", kTrajectoryStage,
                        "--all"}).exit_code, 0);
  EXPECT_FALSE(fs::exists(folder));
  EXPECT_EQ(QueryRows(db, std::string("SELECT COUNT(*) FROM artifacts WHERE stage = '") +
                              kTrajectoryStage + "'")[0], "0");
  // A hand that does not exist: refused when the config loads, no attempt spent.
  WriteFile(work_ / "bad_hand.toml", BundleConfig() + "[retarget_kinematic]\nhand = \"no_such_hand\"\n");
  const auto bad = RunDoasido({"run", "--db", db.string(), "--config",
                               (work_ / "bad_hand.toml").string()});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_TRUE(Has(bad.err, "retarget_kinematic.hand")) << bad.err;
  EXPECT_EQ(QueryRows(db, std::string("SELECT MAX(attempts) FROM stage_runs WHERE stage = '") +
                              kTrajectoryStage + "'")[0], "0");
  // A run that fails: its reconstruction and its bundle are gone.
  for (const auto& clip : clips) {
    fs::remove_all(work_ / "w/artifacts" / clip / "recon" / "reconstruction.npz");
    fs::remove_all(work_ / "w/artifacts" / clip / "bundle" / "meta.json");
  }
  RunDoasido({"run", "--db", db.string(), "--config", (*pool_ / "run.toml").string()});
  EXPECT_EQ(QueryRows(db, std::string("SELECT COUNT(*) FROM stage_runs WHERE stage = '") +
                              kTrajectoryStage + "' AND state = 'done'")[0], "0");
  EXPECT_FALSE(fs::exists(folder));
  for (const auto& entry : fs::directory_iterator(work_ / "w/artifacts" / clips[0])) {
    EXPECT_NE(entry.path().filename().string()[0], '.') << "leftover " << entry.path();
  }
  const auto plan = RunDoasido({"deploy", "plan", "--db", db.string(), "--clip", clips[0], "--out",
                                (work_ / "plan.json").string()});
  EXPECT_NE(plan.exit_code, 0);
  EXPECT_TRUE(Has(plan.err, "not done")) << plan.err;
  EXPECT_FALSE(fs::exists(work_ / "plan.json"));
}

// Findings 3 and 7 (self-merge, a non-database, relative measurements).
TEST_F(CliArtifacts, MergeCopiesAndHoldsBackAClipWithAMissingFile) {
  const fs::path db = work_ / "p" / "d.db";
  fs::create_directories(db.parent_path());
  ASSERT_EQ(RunDoasido({"init", "--db", db.string(), "--pipeline", kPipeline}).exit_code, 0);
  ASSERT_EQ(RunDoasido({"ingest", "--db", db.string(), (*pool_ / "s").string()}).exit_code, 0);
  const auto sharded = RunDoasido({"shard", "--db", db.string(), "--shards", "1", "--out",
                                   (work_ / "sh").string(), "--config",
                                   (*pool_ / "run.toml").string()});
  ASSERT_EQ(sharded.exit_code, 0) << sharded.err;
  const fs::path shard = work_ / "sh/shard-000/doasido.db";
  const auto run = RunDoasido({"run", "--db", shard.string(), "--config",
                               (*pool_ / "run.toml").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto clips = DoneTrajectoryClips(shard);
  ASSERT_GE(clips.size(), 2u);
  const fs::path lost = work_ / "sh/shard-000/artifacts" / clips[0] / kTrajectoryStage / "trajectory.csv";
  ASSERT_TRUE(fs::exists(lost));
  fs::remove(lost);

  const auto merged = RunDoasido({"merge", "--db", db.string(), shard.string()});
  EXPECT_NE(merged.exit_code, 0);
  EXPECT_TRUE(Has(merged.err, lost.string())) << merged.err;
  // The held-back clip is not merged; the others are, with their own copies.
  EXPECT_TRUE(QueryRows(db, "SELECT 1 FROM stage_runs WHERE clip_id = " + clips[0] +
                                " AND state = 'done'").empty());
  const fs::path mine = work_ / "p/artifacts" / clips[1] / kTrajectoryStage / "trajectory.json";
  const fs::path theirs = work_ / "sh/shard-000/artifacts" / clips[1] / kTrajectoryStage / "trajectory.json";
  ASSERT_TRUE(fs::exists(mine));
  EXPECT_EQ(fs::hard_link_count(mine), 1u);
  EXPECT_FALSE(fs::equivalent(mine, theirs));
  const std::string before = ingest::FileSha256(mine);
  std::ofstream(theirs, std::ios::app) << " ";  // the shard's file changes later
  EXPECT_EQ(ingest::FileSha256(mine), before);
  // Paths in merged measurements are relative to the artifact root.
  for (const auto& data : QueryRows(db, "SELECT data FROM measurements WHERE stage = 'recon'")) {
    EXPECT_FALSE(Has(data, (work_ / "sh").string())) << data;
  }
  // Self-merge and a non-database, each refused naming the right file.
  const auto self = RunDoasido({"merge", "--db", db.string(), db.string()});
  EXPECT_NE(self.exit_code, 0);
  EXPECT_TRUE(Has(self.err, "self_merge")) << self.err;
  WriteFile(work_ / "notes.txt", "not a database\n");
  const auto text = RunDoasido({"merge", "--db", db.string(), (work_ / "notes.txt").string()});
  EXPECT_NE(text.exit_code, 0);
  EXPECT_TRUE(Has(text.err, (work_ / "notes.txt").string())) << text.err;
}

// A merge is atomic for every reader: files are staged, the rows commit
// with a placement journal, and a merge killed after its commit (here: the
// journal committed by a process that is gone, one folder already moved)
// is finished by the next open of the database; staging left by a merge
// killed before its commit is removed by the next merge.
TEST_F(CliArtifacts, AMergeKilledAfterItsCommitIsFinishedByTheNextOpen) {
  const fs::path db = work_ / "p" / "d.db";
  fs::create_directories(db.parent_path());
  ASSERT_EQ(RunDoasido({"init", "--db", db.string(), "--pipeline", kPipeline}).exit_code, 0);
  ASSERT_EQ(RunDoasido({"ingest", "--db", db.string(), (*pool_ / "s").string()}).exit_code, 0);
  ASSERT_EQ(RunDoasido({"shard", "--db", db.string(), "--shards", "1", "--out", (work_ / "sh").string(),
                        "--config", (*pool_ / "run.toml").string()}).exit_code, 0);
  const fs::path shard = work_ / "sh/shard-000/doasido.db";
  ASSERT_EQ(RunDoasido({"run", "--db", shard.string(), "--config", (*pool_ / "run.toml").string()}).exit_code, 0);
  const fs::path theirs = shard.parent_path() / "artifacts";
  const fs::path mine = db.parent_path() / "artifacts";
  const pid_t gone = fork();  // a process id that no longer runs
  if (gone == 0) _exit(0);
  waitpid(gone, nullptr, 0);
  // Killed before its commit: staging nobody names.
  const fs::path stale = mine / (".merge-" + std::to_string(gone) + "-0000abcd");
  WriteFile(stale / "1/recon/half.json", "{");

  // The state a kill right after the commit leaves: rows merged, journal
  // recorded, files still staged (one already moved).
  const std::string staging = ".merge-" + std::to_string(gone) + "-0000beef";
  Database::MergePlacement placement{.staging = staging, .pid = gone};
  for (const auto& clip : fs::directory_iterator(theirs)) {
    const std::string c = clip.path().filename().string();
    if (c[0] == '.' || !clip.is_directory()) continue;
    for (const auto& stage : fs::directory_iterator(clip.path())) {
      fs::create_directories(mine / staging / c);
      fs::copy(stage.path(), mine / staging / c / stage.path().filename(), fs::copy_options::recursive);
      placement.place.emplace_back(std::stoll(c), stage.path().filename().string());
    }
  }
  ASSERT_GE(placement.place.size(), 4u);
  {
    Database parent(db);
    parent.MergeShard(shard, {}, Database::PlacementJson(placement));
  }
  const auto& [first_clip, first_stage] = placement.place.front();
  fs::create_directories(mine / std::to_string(first_clip));
  fs::rename(mine / staging / std::to_string(first_clip) / first_stage,
             mine / std::to_string(first_clip) / first_stage);
  ASSERT_FALSE(QueryRows(db, "SELECT value FROM meta WHERE key = 'pending_placement'").empty());
  const auto clips = DoneTrajectoryClips(db);
  ASSERT_GE(clips.size(), 2u);

  // Any command's open finishes it.
  ASSERT_EQ(RunDoasido({"status", "--db", db.string()}).exit_code, 0);
  EXPECT_TRUE(QueryRows(db, "SELECT value FROM meta WHERE key = 'pending_placement'").empty());
  EXPECT_FALSE(fs::exists(mine / staging));
  for (const auto& [clip, stage] : placement.place) {
    const fs::path rel = fs::path(std::to_string(clip)) / stage;
    for (const auto& f : fs::recursive_directory_iterator(theirs / rel)) {
      if (!f.is_regular_file()) continue;
      const fs::path placed = mine / rel / fs::relative(f.path(), theirs / rel);
      ASSERT_TRUE(fs::exists(placed)) << placed;
      EXPECT_EQ(ingest::FileSha256(placed), ingest::FileSha256(f.path())) << placed;
    }
  }
  // A plan reads the merged trajectory.
  const auto plan = RunDoasido({"deploy", "plan", "--db", db.string(), "--clip", clips[0], "--no-replay",
                                "--yaw-steps", "1", "--offset-steps", "1", "--out", (work_ / "plan.json").string()});
  EXPECT_TRUE(fs::exists(work_ / "plan.json")) << plan.err;
  // The stale staging is the next merge's to remove; the merge is a no-op.
  EXPECT_TRUE(fs::exists(stale));
  const auto again = RunDoasido({"merge", "--db", db.string(), shard.string()});
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_FALSE(fs::exists(stale));
}

// Finding 4.
TEST_F(CliArtifacts, AVerificationCountsOnlyForTheTrajectorySeen) {
  const fs::path db = CopyBase(work_ / "w");
  const auto clips = DoneTrajectoryClips(db);
  ASSERT_FALSE(clips.empty());
  const ClipId clip = std::stoll(clips[0]);
  const fs::path trajectory = work_ / "w/artifacts" / clips[0] / kTrajectoryStage / "trajectory.json";
  {
    Database d(db);
    d.RecordVerification(clip, kTrajectoryStage, "alice", true, "", ingest::FileSha256(trajectory));
  }
  const std::string root = (work_ / "ds").string();
  ASSERT_EQ(RunDoasido({"dataset", "create", "--db", db.string(), "--root", root, "--select",
                        "verified", "--no-thumbnails"}).exit_code, 0);
  const auto v1 = dataset::ReadManifest(work_ / "ds/default/v1");
  ASSERT_EQ(v1.episodes.size(), 1u);
  ASSERT_TRUE(v1.episodes[0].verification.has_value());
  EXPECT_EQ(v1.episodes[0].verification->reviewer, "alice");
  // Re-retargeted with other parameters: a new trajectory nobody saw.
  ASSERT_EQ(RunDoasido({"queue", "reset", "--db", db.string(), "--stage", kTrajectoryStage,
                        "--clip", clips[0]}).exit_code, 0);
  WriteFile(work_ / "other.toml", BundleConfig() + "[retarget_kinematic.kinematic]\nsmooth_weight = 3.0\n");
  ASSERT_EQ(RunDoasido({"run", "--db", db.string(), "--config", (work_ / "other.toml").string()})
                .exit_code, 0);
  ASSERT_NE(ingest::FileSha256(trajectory), QueryRows(db, "SELECT artifact_sha256 FROM reviews")[0]);
  ASSERT_EQ(RunDoasido({"dataset", "create", "--db", db.string(), "--root", root, "--select",
                        "all", "--no-thumbnails"}).exit_code, 0);
  const auto v2 = dataset::ReadManifest(work_ / "ds/default/v2");
  for (const auto& e : v2.episodes) EXPECT_FALSE(e.verification.has_value()) << e.id;
  const auto v3 = RunDoasido({"dataset", "create", "--db", db.string(), "--root", root,
                              "--select", "verified", "--no-thumbnails"});
  EXPECT_NE(v3.exit_code, 0);  // nothing verified is left
  EXPECT_FALSE(fs::exists(work_ / "ds/default/v3"));
}

// Findings 5 and 3 (a missing episode file).
TEST_F(CliArtifacts, VersionsProveThemselvesAndExportVerifiesFirst) {
  const fs::path db = CopyBase(work_ / "w");
  const auto clips = DoneTrajectoryClips(db);
  ASSERT_GE(clips.size(), 2u);
  const std::string root = (work_ / "ds").string();
  auto create = [&] {
    return RunDoasido({"dataset", "create", "--db", db.string(), "--root", root, "--select", "all",
                       "--no-thumbnails"});
  };
  ASSERT_EQ(create().exit_code, 0);
  // A missing trajectory file leaves that episode out, named, not the version.
  fs::remove(work_ / "w/artifacts" / clips[0] / kTrajectoryStage / "trajectory.json");
  const auto v2 = create();
  ASSERT_EQ(v2.exit_code, 0) << v2.err;
  EXPECT_TRUE(Has(v2.err, "left out clip " + clips[0])) << v2.err;
  const auto m2 = dataset::ReadManifest(work_ / "ds/default/v2");
  EXPECT_EQ(m2.episodes.size(), clips.size() - 1);
  // An edited split: verify and show refuse, list names it and keeps v1.
  const fs::path manifest = work_ / "ds/default/v2/manifest.json";
  std::string text = ReadFile(manifest);
  const auto at = text.find("\"train\"");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 7, "\"test\" ");
  WriteFile(manifest, text);
  const auto verify = RunDoasido({"dataset", "verify", "--root", root, "v2"});
  EXPECT_NE(verify.exit_code, 0);
  EXPECT_TRUE(Has(verify.err, "manifest was edited")) << verify.err;
  EXPECT_NE(RunDoasido({"dataset", "show", "--root", root, "v2"}).exit_code, 0);
  WriteFile(work_ / "ds/default/v1/manifest.json", "{ not json");
  fs::create_directories(work_ / "ds/default/v3/episodes");  // a stray folder, no manifest
  const auto list = RunDoasido({"dataset", "list", "--root", root});
  EXPECT_EQ(list.exit_code, 0) << list.err;
  EXPECT_TRUE(Has(list.out, "v1     BROKEN")) << list.out;
  EXPECT_TRUE(Has(list.out, "v2     BROKEN")) << list.out;
  EXPECT_TRUE(Has(list.out, "v3 is not a version")) << list.out;
  const auto v4 = create();
  ASSERT_EQ(v4.exit_code, 0) << v4.err;
  EXPECT_TRUE(Has(v4.err, "v3 is not a version")) << v4.err;
  EXPECT_TRUE(fs::exists(work_ / "ds/default/v4/manifest.sha256"));
  EXPECT_TRUE(Has(RunDoasido({"dataset", "list", "--root", root}).out, "default          v4"));
  // A changed digit in an episode: export refuses; --no-verify says so.
  const auto m4 = dataset::ReadManifest(work_ / "ds/default/v4");
  const fs::path episode = work_ / "ds/default/v4/episodes" / m4.episodes[0].id / "trajectory.csv";
  std::string csv = ReadFile(episode);
  const auto digit = csv.find_first_of("123456789", csv.find('\n'));
  csv[digit] = csv[digit] == '9' ? '8' : static_cast<char>(csv[digit] + 1);
  WriteFile(episode, csv);
  const fs::path out = work_ / "demo.hdf5";
  const auto refused = RunDoasido({"dataset", "export", "--root", root, "v4", "--format",
                                   "robomimic", "--out", out.string()});
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_TRUE(Has(refused.err, episode.string())) << refused.err;
  EXPECT_FALSE(fs::exists(out));
  const auto forced = RunDoasido({"dataset", "export", "--root", root, "v4", "--format",
                                  "robomimic", "--out", out.string(), "--no-verify"});
  EXPECT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_TRUE(Has(forced.err, "--no-verify")) << forced.err;
  EXPECT_TRUE(fs::exists(out));
}

// Finding 6: SIGKILL at random moments of an export, new and replacing.
TEST_F(CliArtifacts, AKilledExportLeavesTheOldOneOrTheNewOneWhole) {
  const fs::path db = CopyBase(work_ / "w");
  const std::string root = (work_ / "ds").string();
  ASSERT_EQ(RunDoasido({"dataset", "create", "--db", db.string(), "--root", root, "--select", "all",
                        "--no-thumbnails"}).exit_code, 0);
  std::mt19937 rng(36);
  for (const std::string format : {"lerobot", "robomimic"}) {
    const fs::path out = work_ / ("out-" + format);
    const std::vector<std::string> args = {"dataset", "export", "--root", root, "v1", "--format",
                                           format, "--out", out.string(), "--no-videos"};
    // A reference export: its time bounds the kills.
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(RunDoasido(args).exit_code, 0);
    const double full_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string marker = format == "lerobot" ? "meta/info.json" : "";
    auto whole = [&] {
      return format == "lerobot" ? fs::exists(out / marker) && fs::exists(out / "meta/doasido_manifest.json")
                                 : testing::ShellOk("/usr/bin/python3 -c \"import h5py; f = h5py.File('" + out.string() +
                                           "'); print(len(f['data']))\"") != "";
    };
    for (int kill = 0; kill < 3; ++kill) {
      const bool replacing = kill % 2 == 0;
      if (!replacing) fs::remove_all(out);
      std::vector<std::string> argv = {testing::DoasidoBin().string()};
      argv.insert(argv.end(), args.begin(), args.end());
      const int pid = testing::Spawn(argv, work_ / "export.log");
      std::uniform_real_distribution<double> when(0.0, full_s);
      std::this_thread::sleep_for(std::chrono::duration<double>(when(rng)));
      ::kill(pid, SIGKILL);
      testing::WaitFor(pid);
      if (fs::exists(out)) {
        EXPECT_TRUE(whole()) << format << " kill " << kill << ": a part of an export";
      } else {
        EXPECT_FALSE(replacing) << format << " kill " << kill << ": the old export is gone";
      }
      ASSERT_EQ(RunDoasido(args).exit_code, 0) << format << " re-run after kill " << kill;
      EXPECT_TRUE(whole());
      for (const auto& entry : fs::directory_iterator(work_ / "")) {
        EXPECT_FALSE(Has(entry.path().filename().string(), ".tmp-")) << entry.path();
      }
    }
  }
}

// Finding 7: no stage leaves an empty folder per clip.
TEST_F(CliArtifacts, NoEmptyArtifactFolders) {
  for (const auto& entry : fs::recursive_directory_iterator(*pool_ / "base" / "artifacts")) {
    if (entry.is_directory()) {
      EXPECT_FALSE(fs::is_empty(entry.path())) << entry.path();
    }
  }
  EXPECT_TRUE(fs::exists(*pool_ / "base/artifacts" / Database::kArtifactOwnerFile));
}

}  // namespace
}  // namespace doasido
