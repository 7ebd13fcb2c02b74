// The review page shows the span the shot filter kept: for a clip the shot
// stage rejected across a cut, the later filters judge its longest segment,
// and the page's trim must be that same segment (it used to be blank there).
#include <gtest/gtest.h>
#include <httplib.h>

#include <filesystem>

#include "db/database.h"
#include "filters/analyze.h"
#include "filters/verdict.h"
#include "review/server.h"
#include "stages/analyze_stage.h"
#include "stages/verdict_stages.h"
#include "tests/test_util.h"

namespace doasido::review {
namespace {

using testing::SharedData;
using testing::TempDir;

TEST(ReviewKeptShot, ThePageSpanIsTheShotTheFiltersJudged) {
  TempDir dir;
  const std::filesystem::path db_path = dir / "d.db";
  ClipId clip = 0;
  {
    Database db(db_path);
    db.SetPipeline({filters::kAnalyzeStageName, filters::kShotBoundaryStageName,
                    filters::kInteractionStageName});
    ClipRecord c;
    c.video_id = db.UpsertVideo((SharedData() / "shots" / "testvideo.mp4").string());
    c.external_id = "cut";
    clip = db.InsertClip(c).id;
    // Shots must last 1000 s: the shot stage rejects the clip across its cuts
    // and keeps no trim, so the longest segment is what later filters judge.
    filters::ShotBoundaryConfig strict;
    strict.min_segment_s = 1000;
    stages::AnalyzeStage analyze;
    stages::ShotBoundaryStage shots(strict);
    for (stages::Stage* stage : std::initializer_list<stages::Stage*>{&analyze, &shots}) {
      const auto claim = db.ClaimNext("w", {stage->Name()}, 60, 3);
      ASSERT_TRUE(claim) << stage->Name();
      const ClipContext context = db.LoadContext(clip, stage->Name());
      std::filesystem::create_directories(context.artifact_dir);
      ASSERT_TRUE(db.Complete(*claim, "w", "h", stage->Run(context), 0));
    }
  }
  Database db(db_path);
  const auto runs = db.ListRuns({.stage = filters::kShotBoundaryStageName});
  ASSERT_EQ(runs.size(), 1u);
  ASSERT_EQ(runs[0].verdict, "reject");
  const Json shot = *db.GetMeasurements(clip, filters::kShotBoundaryStageName);
  const Json& summary = shot.at("summary");
  ASSERT_FALSE(summary.at("boundaries").empty());
  ASSERT_FALSE(summary.contains("trim"));

  ClipContext later;
  later.measurements[filters::kAnalyzeStageName] =
      *db.GetMeasurements(clip, filters::kAnalyzeStageName);
  later.measurements[filters::kShotBoundaryStageName] = shot;
  const Json judged = stages::CopyAnalysis(later, filters::kInteractionStageName).at("shot");
  EXPECT_EQ(judged.at("trim").at("start_frame"), summary.at("longest_segment").at("start_frame"));
  EXPECT_EQ(judged.at("trim").at("end_frame"), summary.at("longest_segment").at("end_frame"));

  ReviewServer server(db_path, ServeOptions{.port = 0});
  httplib::Client client("127.0.0.1", server.Start());
  const auto page = client.Get("/api/clip/" + std::to_string(clip) + "?stage=" +
                               filters::kShotBoundaryStageName);
  ASSERT_TRUE(page);
  ASSERT_EQ(page->status, 200) << page->body;
  const Json c = Json::parse(page->body);
  ASSERT_TRUE(c.at("trim").is_object()) << c.dump();
  EXPECT_EQ(c.at("trim").at("start_frame"), judged.at("trim").at("start_frame"));
  EXPECT_EQ(c.at("trim").at("end_frame"), judged.at("trim").at("end_frame"));
  EXPECT_EQ(c.at("cuts"), judged.at("boundaries"));
}

}  // namespace
}  // namespace doasido::review
