// No verdict without its evidence, through the queue: a real clip the
// camera-motion verdict rejects before the hand models run (models deferred,
// the default) records not_measured at the hand stages, naming
// camera_motion, and stops at camera_motion with its reason; it waits in no
// review queue; a rethreshold that un-rejects it sends it back to the
// analysis for the measurement it lacks, and the worker then measures and
// judges it.
#include <gtest/gtest.h>

#include "db/database.h"
#include "filters/analyze.h"
#include "filters/hand_landmarker.h"
#include "pipeline/rethreshold.h"
#include "pipeline/worker.h"
#include "stages/stage_registry.h"
#include "test_util.h"

namespace doasido {
namespace {

using namespace doasido::filters;

const std::vector<std::string> kHandStages = {kInteractionStageName, kOutOfFrameStageName,
                                              kActivityStageName};

std::map<std::string, StageRunRow> RunsOf(Database& db, ClipId clip) {
  std::map<std::string, StageRunRow> out;
  for (const StageRunRow& r : db.ListRuns({.clip = clip})) out[r.stage] = r;
  return out;
}

void RunUntilEmpty(const std::string& db, const Json& config) {
  pipeline::WorkerOptions options;
  options.db = db;
  options.config = config;
  options.until_empty = true;
  options.poll_s = 0.01;
  pipeline::RunWorkerLoop(options);
}

TEST(NotMeasured, ACameraMotionRejectLeavesTheHandStagesUnmeasuredUntilARethresholdKeepsIt) {
  std::string why;
  if (!HandLandmarkerAvailable(&why)) GTEST_SKIP() << why;
  testing::TempDir dir;
  const std::string path = (dir / "d.db").string();
  ClipId clip = 0;
  {
    Database db(path);
    const std::vector<std::string> stages = {kAnalyzeStageName,  kShotBoundaryStageName,
                                             kInteractionStageName, kOutOfFrameStageName,
                                             kActivityStageName, kCameraMotionStageName};
    db.SetPipeline(stages, stages::FlagContinuingStages(stages));
    // apple: the camera circles an apple on a table (rejected for camera
    // motion; ../shared/data/README.md).
    ClipRecord c;
    c.video_id = db.UpsertVideo((testing::SharedData() / "videos" / "apple.mp4").string());
    c.external_id = "apple";
    clip = db.InsertClip(c).id;
  }
  RunUntilEmpty(path, Json::object());  // the defaults: models after the cheap verdicts

  Database db(path);
  auto runs = RunsOf(db, clip);
  ASSERT_EQ(runs.count(kCameraMotionStageName), 1u);
  EXPECT_EQ(runs.at(kCameraMotionStageName).verdict, "reject");
  EXPECT_EQ(runs.at(kCameraMotionStageName).reason, kReasonCameraMotion);
  for (const std::string& stage : kHandStages) {
    ASSERT_EQ(runs.count(stage), 1u) << stage;
    EXPECT_EQ(runs.at(stage).state, RunState::kDone) << stage;
    EXPECT_EQ(runs.at(stage).verdict, ToString(Verdict::kNotMeasured)) << stage;
    EXPECT_EQ(runs.at(stage).reason, kCameraMotionStageName) << stage;
    // The stored measurements hold no signals a later rule could judge.
    const auto m = db.GetMeasurements(clip, stage);
    ASSERT_TRUE(m);
    EXPECT_FALSE(m->contains("signals")) << stage;
    EXPECT_EQ(m->at(kNotMeasuredKey).at("stage"), kCameraMotionStageName);
  }
  const auto analysis = db.GetMeasurements(clip, kAnalyzeStageName);
  ASSERT_TRUE(analysis);
  EXPECT_FALSE(analysis->contains(kHandsMeasurement));
  for (const std::string& stage : kHandStages) EXPECT_FALSE(analysis->contains(stage)) << stage;

  // In no review queue: nothing was flagged for a person.
  for (const auto& f : db.ListFlagged()) EXPECT_NE(f.clip_id, clip) << f.stage;
  EXPECT_EQ(db.CountFlagged(), 0);

  // A hand stage re-decided keeps not_measured (nothing to decide from).
  const Json lenient = {{kInteractionStageName, {{"min_interaction_fraction", 0.0}}},
                        {kCameraMotionStageName,
                         {{"reject_translation_rate", 10.0}, {"flag_translation_rate", 5.0},
                          {"reject_rotation_rate", 10.0}, {"flag_rotation_rate", 5.0},
                          {"reject_scale_rate", 10.0}, {"flag_scale_rate", 5.0},
                          {"reject_peak_translation_rate", 100.0},
                          {"reject_peak_rotation_rate", 100.0}, {"reject_peak_scale_rate", 100.0},
                          {"min_valid_fraction", 0.0}}}};
  const auto interaction = pipeline::RethresholdStage(db, kInteractionStageName, lenient, false);
  EXPECT_EQ(interaction.remeasure, 0);
  EXPECT_EQ(RunsOf(db, clip).at(kInteractionStageName).verdict,
            ToString(Verdict::kNotMeasured));

  // A camera-motion threshold that keeps the clip sends it back for the
  // measurement it lacks: the analysis is queued again, nothing after it
  // stands (no hand stage decided from the absent measurement).
  const auto camera = pipeline::RethresholdStage(db, kCameraMotionStageName, lenient, false);
  EXPECT_EQ(camera.remeasure, 1);
  runs = RunsOf(db, clip);
  ASSERT_EQ(runs.count(kAnalyzeStageName), 1u);
  EXPECT_EQ(runs.at(kAnalyzeStageName).state, RunState::kPending);
  for (const auto& [stage, run] : runs) {
    EXPECT_EQ(stage, kAnalyzeStageName) << "a run after the analysis stands: " << stage;
  }
  for (const std::string& stage : kHandStages) {
    for (const auto& v : db.VerdictHistory(clip, stage)) {
      EXPECT_EQ(v.verdict, ToString(Verdict::kNotMeasured)) << stage;
    }
  }

  // The worker, with the same thresholds, now measures the hands and every
  // hand stage judges them.
  RunUntilEmpty(path, lenient);
  runs = RunsOf(db, clip);
  const auto remeasured = db.GetMeasurements(clip, kAnalyzeStageName);
  ASSERT_TRUE(remeasured);
  EXPECT_FALSE(remeasured->contains(kNotMeasuredKey)) << remeasured->at("clip").dump();
  EXPECT_TRUE(remeasured->contains(kHandsMeasurement)) << remeasured->at("clip").dump();
  ASSERT_EQ(runs.count(kInteractionStageName), 1u);
  EXPECT_EQ(runs.at(kInteractionStageName).state, RunState::kDone);
  EXPECT_NE(runs.at(kInteractionStageName).verdict, ToString(Verdict::kNotMeasured));
  for (const auto& [stage, run] : runs) {
    EXPECT_NE(run.verdict, ToString(Verdict::kNotMeasured)) << stage;
  }
}

TEST(NotMeasured, TheVerdictKindRoundTripsAndOlderDatabasesTakeIt) {
  EXPECT_EQ(VerdictFromString(ToString(Verdict::kNotMeasured)), Verdict::kNotMeasured);
  testing::TempDir dir;
  Database db((dir / "d.db").string());
  db.SetPipeline({"a", "b"});
  ClipRecord c;
  c.video_id = db.UpsertVideo("/videos/x.mp4");
  const ClipId clip = db.InsertClip(c).id;
  const auto claim = db.ClaimNext("w", {}, 60, 3);
  ASSERT_TRUE(claim);
  StageResult r;
  r.verdict = Verdict::kNotMeasured;
  r.reason = "b";
  ASSERT_TRUE(db.Complete(*claim, "w", "h", r, 0.1));
  // It moves the clip on like a pass.
  const auto runs = RunsOf(db, clip);
  EXPECT_EQ(runs.at("a").verdict, "not_measured");
  ASSERT_EQ(runs.count("b"), 1u);
  EXPECT_EQ(runs.at("b").state, RunState::kPending);
}

}  // namespace
}  // namespace doasido
