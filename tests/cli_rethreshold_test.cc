// `doasido rethreshold` re-decides the filter verdicts from stored
// measurements: with the videos deleted (so nothing can be decoded), the
// new verdicts follow the stored scores and the new thresholds exactly,
// clips a change sends on are judged by the later stages, a person's verdict
// is kept, and a later `doasido run` with the same config has nothing to redo.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <sstream>

#include "db/database.h"
#include "testing/db_dump.h"
#include "test_util.h"

namespace doasido {
namespace {

using testing::RunDoasido;
using testing::DeadPid;
using testing::TempDir;

TEST(Rethreshold, RedecidesFromStoredMeasurementsWithoutTheVideos) {
  TempDir dir;
  const std::string out = (dir / "synth").string();
  ASSERT_EQ(RunDoasido({"synth", "--out", out, "--clips", "12", "--frames", "60", "--width",
                        "160", "--height", "120", "--seed", "5", "--mix",
                        "clean=0.4,static=0.2,cut=0.2,pan=0.2"})
                .exit_code,
            0);
  const std::string db_path = (dir / "d.db").string();
  ASSERT_EQ(RunDoasido({"init", "--db", db_path, "--pipeline", "filters"}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", db_path, out + "/Annotations"});
  ASSERT_EQ(run.exit_code, 0) << run.err;

  std::map<std::pair<ClipId, std::string>, int> done_before;
  ClipId human_clip = 0;
  {
    Database db(db_path);
    done_before = db.DoneEventCounts();
    // A person rejects one clip that interaction passed.
    for (const auto& r : db.ListRuns({.stage = "interaction", .state = "done"})) {
      if (r.verdict == "pass") human_clip = r.clip_id;
    }
    ASSERT_NE(human_clip, 0);
    db.SetVerdict(human_clip, "interaction", Verdict::kReject, "blurry", "human");
  }
  std::filesystem::remove_all(out + "/videos");  // nothing can be decoded now

  testing::WriteFile(dir / "strict.toml",
                     "[interaction]\nmin_interaction_fraction = 0.0\n"
                     "[activity]\nmin_active_fraction = 0.9\n");
  const auto dry = RunDoasido({"rethreshold", "--db", db_path, "--config",
                               (dir / "strict.toml").string(), "--dry-run"});
  ASSERT_EQ(dry.exit_code, 0) << dry.err;
  EXPECT_NE(dry.out.find("nothing written"), std::string::npos);
  {  // The dry run counts the person's verdict as kept, not re-decided.
    std::istringstream lines(dry.out);
    std::string line;
    bool seen = false;
    while (std::getline(lines, line)) {
      std::istringstream cells(line);
      std::string stage;
      long long redecided = 0, unchanged = 0, person = -1, judged = 0;
      if (cells >> stage >> redecided >> unchanged >> person >> judged && stage == "interaction") {
        EXPECT_EQ(person, 1) << line;
        seen = true;
      }
    }
    EXPECT_TRUE(seen) << dry.out;
  }
  const auto re =
      RunDoasido({"rethreshold", "--db", db_path, "--config", (dir / "strict.toml").string()});
  ASSERT_EQ(re.exit_code, 0) << re.err << re.out;

  Database db(db_path);
  int interaction_runs = 0, activity_runs = 0, activity_rejects = 0;
  for (const auto& r : db.ListRuns({.stage = "interaction"})) {
    ++interaction_runs;
    EXPECT_EQ(r.state, "done");
    EXPECT_EQ(r.verdict, r.clip_id == human_clip ? "reject" : "pass") << r.clip_id;
  }
  int shot_passes = 0;  // interaction judges exactly the clips the shot filter passed
  for (const auto& r : db.ListRuns({.stage = "shot_boundary"})) shot_passes += r.verdict == "pass";
  EXPECT_EQ(interaction_runs, shot_passes);
  EXPECT_GT(interaction_runs, 6);
  for (const auto& r : db.ListRuns({.stage = "activity"})) {
    ++activity_runs;
    ASSERT_EQ(r.state, "done") << r.clip_id << " " << r.error;
    const Json m = *db.GetMeasurements(r.clip_id, "activity");
    const double active = m.at("summary").at("active_fraction").get<double>();
    EXPECT_EQ(r.verdict, active < 0.9 ? "reject" : "pass") << r.clip_id << " " << active;
    activity_rejects += r.verdict == "reject";
    // The stored score carries the new threshold.
    EXPECT_DOUBLE_EQ(m.at("summary").at("scores").at(0).at("reject").get<double>(), 0.9);
  }
  EXPECT_GT(activity_runs, 0);
  EXPECT_GT(activity_rejects, 0);
  // The analysis stage (the only one that decodes) did not run again.
  const auto done_after = db.DoneEventCounts();
  for (const auto& [key, n] : done_after) {
    if (key.second == "filters_analyze" || key.second == "probe") {
      EXPECT_EQ(n, done_before.at(key)) << key.first << " " << key.second;
    }
  }
  // Same parameters again: nothing left to do for the worker.
  const auto again = RunDoasido({"run", "--db", db_path, "--config", (dir / "strict.toml").string()});
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(db.DoneEventCounts(), done_after);
}

// A filtered pool whose activity runs are queued again; `copies` databases
// of it in their own folders.
std::vector<std::string> RequeuedActivity(const TempDir& dir, int copies) {
  const std::string out = (dir / "synth").string();
  EXPECT_EQ(RunDoasido({"synth", "--out", out, "--clips", "6", "--frames", "40", "--width", "128",
                        "--height", "96", "--seed", "9", "--mix", "clean=0.6,static=0.4"})
                .exit_code,
            0);
  const std::string db_path = (dir / "d.db").string();
  EXPECT_EQ(RunDoasido({"init", "--db", db_path}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", db_path, out + "/Annotations"});
  EXPECT_EQ(run.exit_code, 0) << run.err;
  const auto reset =
      RunDoasido({"queue", "reset", "--db", db_path, "--stage", "activity", "--all"});
  EXPECT_EQ(reset.exit_code, 0) << reset.err;
  std::vector<std::string> dbs;
  for (int i = 0; i < copies; ++i) {
    const auto folder = dir / ("copy" + std::to_string(i));
    std::filesystem::create_directories(folder);
    std::filesystem::copy_file(db_path, folder / "d.db");
    dbs.push_back((folder / "d.db").string());
  }
  return dbs;
}

std::vector<std::string> Runs(const std::string& db) {
  return testing::QueryRows(db, "SELECT clip_id, stage, state, IFNULL(verdict, ''),"
                                " IFNULL(reason, '') FROM stage_runs ORDER BY clip_id, position");
}

// Issue #50, finding 4: a killed `rethreshold` left its claim `running`, and
// a re-run within the lease exited 0 without finishing it. The claim names
// its process now: a re-run takes a dead one over at once and ends with
// the database of an uninterrupted run; a live holder's claim is waited
// for, and said so.
TEST(Rethreshold, AReRunTakesOverAKilledRunsClaim) {
  TempDir dir;
  const auto dbs = RequeuedActivity(dir, 3);
  ASSERT_EQ(dbs.size(), 3u);
  const auto whole = RunDoasido({"rethreshold", "--db", dbs[0], "--stages", "activity"});
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  ASSERT_EQ(testing::QueryRows(dbs[0], "SELECT COUNT(*) FROM stage_runs WHERE stage = 'activity'"
                                       " AND state != 'done'")[0],
            "0");
  {  // What a rethreshold killed with its claim held leaves.
    Database db(dbs[1]);
    ASSERT_TRUE(db.ClaimNext(Database::LeaseOwner(DeadPid(), DeadPid()), {"activity"}, 600, 3));
  }
  const auto again = RunDoasido({"rethreshold", "--db", dbs[1], "--stages", "activity"});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.err.find("taking over clip"), std::string::npos) << again.err;
  EXPECT_EQ(Runs(dbs[1]), Runs(dbs[0]));

  {  // A live holder (this test process) with a 2-s lease: waited for.
    Database db(dbs[2]);
    ASSERT_TRUE(db.ClaimNext(Database::LeaseOwner(getpid(), getpid()), {"activity"}, 2, 3));
  }
  const auto waited = RunDoasido({"rethreshold", "--db", dbs[2], "--stages", "activity"});
  ASSERT_EQ(waited.exit_code, 0) << waited.err;
  EXPECT_NE(waited.err.find("waiting for clip"), std::string::npos) << waited.err;
  EXPECT_EQ(Runs(dbs[2]), Runs(dbs[0]));
}

// Issue #50, finding 7: `run` after a killed `run` sat silent for the whole
// lease. A dead worker's run on this machine is taken over at once; a run
// another live worker holds is named with its clip, stage and lease end.
TEST(LeaseWaits, RunTakesOverDeadWorkersAndNamesLiveLeases) {
  TempDir dir;
  const auto dbs = RequeuedActivity(dir, 1);
  ASSERT_EQ(dbs.size(), 1u);
  {
    Database db(dbs[0]);
    ASSERT_TRUE(db.ClaimNext(Database::LeaseOwner(DeadPid(), DeadPid()), {"activity"}, 600, 3));
    ASSERT_TRUE(db.ClaimNext("elsewhere:1/2", {"activity"}, 3, 3));
  }
  const auto run = RunDoasido({"run", "--db", dbs[0]});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("taking over clip"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("'s activity run"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("leased by elsewhere:1/2 until"), std::string::npos) << run.err;
  EXPECT_EQ(testing::QueryRows(dbs[0], "SELECT COUNT(*) FROM stage_runs WHERE state IN"
                                       " ('pending', 'running')")[0],
            "0");
}

TEST(Rethreshold, UnknownStageIsRefused) {
  TempDir dir;
  const std::string db_path = (dir / "d.db").string();
  ASSERT_EQ(RunDoasido({"init", "--db", db_path, "--pipeline", "filters"}).exit_code, 0);
  const auto r = RunDoasido({"rethreshold", "--db", db_path, "--stages", "probe"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("probe"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace doasido
