// Study assignment and summaries on the database: slots held by open
// trials, abandoned trials, and items that fill up meanwhile.
#include "review/study.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "tests/test_util.h"

namespace doasido::review {
namespace {

using testing::TempDir;
using testing::WriteFile;

class StudyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* f : {"s.mp4", "a.mp4", "b.mp4"}) WriteFile(dir_ / f, f);
    WriteFile(dir_ / "items.csv",
              "item_id,source_video,a_video,b_video,a_label,b_label\n"
              "only,s.mp4,a.mp4,b.mp4,ours,base\n");
    db_ = std::make_unique<Database>(dir_ / "d.db");
    CreateStudyFromCsv(*db_, "s", dir_ / "items.csv", 2, 5);
    study_ = *db_->GetStudy("s");
  }
  TempDir dir_;
  std::unique_ptr<Database> db_;
  Database::StudyRecord study_;
};

TEST_F(StudyTest, OpenTrialsHoldTheirSlotUntilAbandoned) {
  const auto t1 = NextTrial(*db_, study_, "r1");
  const auto t2 = NextTrial(*db_, study_, "r2");
  ASSERT_TRUE(t1 && t2);
  EXPECT_EQ(NextTrial(*db_, study_, "r1")->id, t1->id) << "an open trial is resumed";
  EXPECT_FALSE(NextTrial(*db_, study_, "r3")) << "both slots are held";
  // Past the abandon time the slots are offered again.
  const auto t3 = NextTrial(*db_, study_, "r3", 0.0);
  ASSERT_TRUE(t3);
  EXPECT_TRUE(db_->AnswerStudyTrial(t3->id, "r3", "left"));
  EXPECT_TRUE(db_->AnswerStudyTrial(t2->id, "r2", "tie"));
  // The item now has its two ratings: r1's late answer is refused, and r1
  // is not offered the item again.
  EXPECT_FALSE(db_->AnswerStudyTrial(t1->id, "r1", "right"));
  EXPECT_FALSE(NextTrial(*db_, study_, "r1"));
  const auto s = SummarizeStudy(*db_, "s");
  EXPECT_EQ(s.ratings, 2);
  EXPECT_EQ(s.complete_items, 1);
  EXPECT_EQ(s.tie, 1);
  EXPECT_EQ(s.a + s.b, 1);
  EXPECT_EQ(s.a, LeftIsA(5, "only", "r3") ? 1 : 0);
  ASSERT_TRUE(s.kappa);
  EXPECT_EQ(s.kappa->subjects, 1);
}

TEST_F(StudyTest, IncompleteItemsStayOutOfKappaAndUnanimity) {
  const auto t1 = NextTrial(*db_, study_, "r1");
  ASSERT_TRUE(t1);
  EXPECT_TRUE(db_->AnswerStudyTrial(t1->id, "r1", "tie"));
  const auto s = SummarizeStudy(*db_, "s");
  EXPECT_EQ(s.ratings, 1);
  EXPECT_DOUBLE_EQ(s.share_tie, 1.0);
  EXPECT_FALSE(s.win_rate_a);
  EXPECT_EQ(s.complete_items, 0);
  EXPECT_FALSE(s.unanimous_share);
  EXPECT_FALSE(s.kappa);
  const Json j = ToJson(s);
  EXPECT_TRUE(j.at("fleiss_kappa").is_null());
  EXPECT_TRUE(j.at("win_rate_a").is_null());
}

TEST_F(StudyTest, LayoutIsSeededPerItemAndRater) {
  int left_a = 0;
  for (int i = 0; i < 200; ++i) {
    const bool v = LeftIsA(5, "item" + std::to_string(i), "ann");
    EXPECT_EQ(v, LeftIsA(5, "item" + std::to_string(i), "ann"));
    left_a += v;
  }
  // A fair coin over 200 trials lands within 100 +- 4 sd (sd ~ 7.1).
  EXPECT_GT(left_a, 71);
  EXPECT_LT(left_a, 129);
  int differs = 0;
  for (int i = 0; i < 64; ++i) {
    differs += LeftIsA(i, "x", "ann") != LeftIsA(i + 1000, "x", "ann");
  }
  EXPECT_GT(differs, 0) << "the seed changes layouts";
}

}  // namespace
}  // namespace doasido::review
