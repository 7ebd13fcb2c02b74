// Schema migration 2 (preference studies) upgrades a version-1 database in
// place: the old rows stay, the study tables appear and work.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include "db/database.h"
#include "db/schema.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::TempDir;

TEST(DbReviewMigration, UpgradesAVersionOneDatabaseInPlace) {
  TempDir dir;
  const auto path = dir / "v1.db";
  // A database exactly as migration 1 left it, with one clip and one review.
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
  const std::string v1 =
      "CREATE TABLE schema_version (version INTEGER NOT NULL);"
      "INSERT INTO schema_version VALUES (1);" +
      db::Migrations().at(0) +
      "INSERT INTO videos (id, path) VALUES (1, 'v.mp4');"
      "INSERT INTO clips (id, video_id, external_id, created_at) VALUES (1, 1, 'old', 0);"
      "INSERT INTO reviews (clip_id, stage, reviewer, decision, reason, created_at)"
      " VALUES (1, 'interaction', 'ann', 'reject', 'no_interaction', 0);";
  char* message = nullptr;
  ASSERT_EQ(sqlite3_exec(raw, v1.c_str(), nullptr, nullptr, &message), SQLITE_OK) << message;
  sqlite3_close(raw);

  Database db(path);
  EXPECT_EQ(db.SchemaVersion(), Database::LatestSchemaVersion());
  EXPECT_EQ(db.GetClip(1).external_id, "old");
  ASSERT_EQ(db.ListReviews().size(), 1u);
  EXPECT_EQ(db.ListReviews()[0].reviewer, "ann");

  Database::StudyRecord study;
  study.name = "s";
  study.raters_per_item = 2;
  const std::int64_t id =
      db.CreateStudy(study, {{.item_id = "i", .source_video = (dir / "s.mp4").string(),
                              .a_video = (dir / "a.mp4").string(),
                              .b_video = (dir / "b.mp4").string(), .a_label = "ours",
                              .b_label = "base"}});
  const auto items = db.GetStudyItems(id);
  ASSERT_EQ(items.size(), 1u);
  EXPECT_EQ(items[0].a_video, (dir / "a.mp4").string());
  const std::int64_t left_b = db.InsertStudyTrial(items[0].id, "r1", false);
  const std::int64_t left_a = db.InsertStudyTrial(items[0].id, "r2", true);
  EXPECT_THROW(db.InsertStudyTrial(items[0].id, "r1", true), Error);
  // The side pressed maps to the method through the trial's layout.
  EXPECT_TRUE(db.AnswerStudyTrial(left_b, "r1", "left"));
  EXPECT_TRUE(db.AnswerStudyTrial(left_a, "r2", "left"));
  EXPECT_FALSE(db.AnswerStudyTrial(left_a, "r2", "right"));  // answered already
  EXPECT_FALSE(db.AnswerStudyTrial(left_b, "r2", "tie"));    // not r2's trial
  EXPECT_EQ(db.GetStudyTrial(left_b)->choice, "b");
  EXPECT_EQ(db.GetStudyTrial(left_a)->choice, "a");
  EXPECT_EQ(db.GetStudyTrial(left_a)->side, "left");
  EXPECT_THROW(db.AnswerStudyTrial(left_a, "r2", "up"), Error);
}

// Migration 3 renames the kinematic retargeting stage in place: its pipeline
// position, runs, measurements and verdicts keep their rows under the new name.
TEST(DbReviewMigration, RenamesTheKinematicStageInPlace) {
  TempDir dir;
  const auto path = dir / "v2.db";
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
  const std::string v2 =
      "CREATE TABLE schema_version (version INTEGER NOT NULL);"
      "INSERT INTO schema_version VALUES (2);" +
      db::Migrations().at(0) + db::Migrations().at(1) +
      "INSERT INTO pipeline VALUES (0, 'probe'), (1, 'retarget-kinematic');"
      "INSERT INTO videos (id, path) VALUES (1, 'v.mp4');"
      "INSERT INTO clips (id, video_id, external_id, created_at) VALUES (1, 1, 'old', 0);"
      "INSERT INTO stage_runs (clip_id, stage, position, state, verdict, param_hash)"
      " VALUES (1, 'retarget-kinematic', 1, 'done', 'flag', 'h');"
      "INSERT INTO measurements VALUES (1, 'retarget-kinematic', 'h', '{\"x\": 1}', 0);";
  char* message = nullptr;
  ASSERT_EQ(sqlite3_exec(raw, v2.c_str(), nullptr, nullptr, &message), SQLITE_OK) << message;
  sqlite3_close(raw);

  Database db(path);
  EXPECT_EQ(db.SchemaVersion(), Database::LatestSchemaVersion());
  EXPECT_EQ(db.Pipeline(), (std::vector<std::string>{"probe", "retarget_kinematic"}));
  const auto m = db.GetMeasurements(1, "retarget_kinematic");
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ((*m)["x"], 1);
  EXPECT_FALSE(db.GetMeasurements(1, "retarget-kinematic").has_value());
  const auto runs = db.ListRuns({});
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].stage, "retarget_kinematic");
}

}  // namespace
}  // namespace doasido
