// `doasido rethreshold` re-decides the filter verdicts from stored
// measurements: with the videos deleted (so nothing can be decoded), the
// new verdicts follow the stored scores and the new thresholds exactly,
// clips a change sends on are judged by the later stages, a person's verdict
// is kept, and a later `doasido run` with the same config has nothing to redo.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

#include "db/database.h"
#include "test_util.h"

namespace doasido {
namespace {

using testing::RunDoasido;
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
