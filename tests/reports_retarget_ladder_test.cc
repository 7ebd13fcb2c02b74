// The report's retargeting section counts what the ladder recorded: clips
// driven through the real queue with measurements written by the ladder's
// own writer (sampler_ladder.h), each clip's rungs known by construction.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "db/database.h"
#include "reports/report.h"
#include "retarget/dynamic/sampler_ladder.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

namespace rt = retarget;
using testing::TempDir;

rt::RungOutcome Rung(const std::string& name, double seconds, bool success) {
  rt::RungOutcome r{name, seconds, {}};
  r.metrics.success = success;
  r.metrics.e_pos = success ? 0.02 : 0.2;
  r.metrics.e_rot = success ? 0.1 : 0.9;
  return r;
}

// What the retarget stage records for one clip: the ladder's rungs (the
// last one kept when it succeeded, else `kept`), or nothing simulated.
Json Measurements(const std::vector<rt::RungOutcome>& rungs, int kept) {
  Json m = Json::object();
  if (rungs.empty()) return m;  // hand-only: the kinematic trajectory kept
  rt::WriteLadderMeasurements(rungs, kept, m);
  m[rt::kMetricSuccess] = rungs[kept].metrics.success;
  return m;
}

TEST(ReportsRetargetLadder, CountsEachRungsRunsSuccessesKeptRunsAndSeconds) {
  TempDir dir;
  Database db(dir / "ladder.db");
  db.SetPipeline({rt::kRetargetStageName});
  const std::vector<Json> clips = {
      Measurements({Rung("fast", 2, true)}, 0),
      Measurements({Rung("fast", 3, false), Rung("medium", 10, true)}, 1),
      Measurements({Rung("fast", 4, false), Rung("medium", 12, false), Rung("seed", 100, false)},
                   1),
      Measurements({Rung("fast", 1, true)}, 0),
      Measurements({}, -1),
  };
  {
    Database::Transaction tx(db);
    for (size_t i = 0; i < clips.size(); ++i) {
      ClipRecord clip;
      clip.video_id = db.UpsertVideo("/nonexistent/v" + std::to_string(i) + ".mp4");
      clip.external_id = "c" + std::to_string(i);
      ASSERT_TRUE(db.InsertClip(clip).inserted);
    }
    tx.Commit();
  }
  for (size_t i = 0; i < clips.size(); ++i) {
    const auto claim = db.ClaimNext("w", {}, 3600, 1);
    ASSERT_TRUE(claim);
    StageResult result;
    result.measurements = clips[std::stoul(db.GetClip(claim->clip_id).external_id.substr(1))];
    ASSERT_TRUE(db.Complete(*claim, "w", "hash", result, 1.0));
  }
  reports::ReportOptions options;
  options.thumbnails = false;
  const reports::ReportOutput out = reports::WriteReport(db, dir / "report", options);
  const reports::RetargetLadderStats& s = out.data.retarget;
  EXPECT_EQ(s.simulated, 4);
  EXPECT_EQ(s.succeeded, 3);
  EXPECT_EQ(s.not_simulated, 1);
  ASSERT_EQ(s.rungs.size(), 3u);
  EXPECT_EQ(s.rungs[0].rung, "fast");
  EXPECT_EQ(s.rungs[0].ran, 4);
  EXPECT_EQ(s.rungs[0].succeeded, 2);
  EXPECT_EQ(s.rungs[0].kept, 2);
  EXPECT_DOUBLE_EQ(s.rungs[0].seconds.total_s, 10);
  EXPECT_EQ(s.rungs[1].rung, "medium");
  EXPECT_EQ(s.rungs[1].ran, 2);
  EXPECT_EQ(s.rungs[1].succeeded, 1);
  EXPECT_EQ(s.rungs[1].kept, 2);  // the clip failing at every rung kept medium's run
  EXPECT_DOUBLE_EQ(s.rungs[1].seconds.mean_s, 11);
  EXPECT_EQ(s.rungs[2].rung, "seed");
  EXPECT_EQ(s.rungs[2].ran, 1);
  EXPECT_EQ(s.rungs[2].kept, 0);
  EXPECT_DOUBLE_EQ(s.rungs[2].seconds.max_s, 100);

  std::ifstream html(out.html);
  std::stringstream page;
  page << html.rdbuf();
  EXPECT_NE(page.str().find("id=\"rungs-table\""), std::string::npos);
  EXPECT_NE(page.str().find("4 clips simulated, 3 succeeded"), std::string::npos);
  const Json json = Json::parse(std::ifstream(out.json));
  EXPECT_EQ(json["retarget"]["rungs"][1]["rung"], "medium");
  EXPECT_EQ(json["retarget"]["rungs"][1]["succeeded"], 1);
  EXPECT_EQ(json["retarget"]["not_simulated"], 1);
}

}  // namespace
}  // namespace doasido
