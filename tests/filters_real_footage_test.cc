// The filters on real footage (../shared/data/videos, see its README):
// 02_cups and 03_blocks are static-camera, single-shot hand-object clips;
// apple is a camera circling an apple with no hands.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "filters/analyze.h"
#include "filters/verdict.h"
#include "stages/verdict_stages.h"
#include "test_util.h"

namespace doasido::filters {
namespace {

using namespace doasido::stages;  // the filters' queue stages

const Json& Analysis(const std::string& name) {
  static std::map<std::string, Json> cache;
  auto it = cache.find(name);
  if (it == cache.end()) {
    // The built-in detector here (the learned one has its own test).
    AnalyzeConfig config;
    config.hand_detector = "builtin";
    ClipAnalysis a =
        AnalyzeClip(testing::SharedData() / "videos" / name, DecoderOptions{}, {}, config);
    it = cache.emplace(name, std::move(a.measurements)).first;
  }
  return it->second;
}

// Runs `stage` the way the worker does: the analysis stage's measurements are
// in the context.
StageResult RunStage(stages::Stage& stage, const std::string& video) {
  ClipContext context;
  context.clip.external_id = video;
  context.video.path = (testing::SharedData() / "videos" / video).string();
  context.measurements[kAnalyzeStageName] = Analysis(video);
  return stage.Run(context);
}

TEST(RealFootage, AnalysisCoversEveryFrameOnce) {
  const Json& clip = Analysis("02_cups.mp4").at("clip");
  EXPECT_EQ(clip.at("frames").get<int>(), 300);
  EXPECT_EQ(clip.at("width").get<int>(), 256);
  EXPECT_EQ(clip.at("height").get<int>(), 144);
  EXPECT_EQ(Analysis("02_cups.mp4").at("shot_boundary").at("delta_hue").size(), 300u);
  EXPECT_EQ(Analysis("02_cups.mp4").at("activity").at("energy").size(), 300u);
  // 5 fps at 29.97 fps: every 6th frame, 49 pairs in 300 frames.
  EXPECT_EQ(Analysis("02_cups.mp4").at("camera_motion").at("step").get<int>(), 6);
  EXPECT_EQ(Analysis("02_cups.mp4").at("camera_motion").at("frame").size(), 49u);
}

TEST(RealFootage, CupsAndBlocksPassShotAndCameraFilters) {
  for (const std::string video : {"02_cups.mp4", "03_blocks.mp4"}) {
    ShotBoundaryStage shots;
    const StageResult s = RunStage(shots, video);
    EXPECT_EQ(s.verdict, Verdict::kPass) << video << " " << s.reason;
    EXPECT_TRUE(s.measurements.at("summary").at("boundaries").empty()) << video;
    EXPECT_FALSE(s.measurements.at("summary").contains("trim")) << video;

    CameraMotionStage camera;
    const StageResult c = RunStage(camera, video);
    EXPECT_EQ(c.verdict, Verdict::kPass)
        << video << " " << c.reason << " " << c.measurements.at("summary").dump();
    // A tripod: under 1% of the diagonal per second.
    EXPECT_LT(c.measurements.at("summary").at("translation_rate").get<double>(), 0.01) << video;
    EXPECT_GE(c.measurements.at("summary").at("valid_fraction").get<double>(), 0.9) << video;

    ActivityStage activity;
    EXPECT_EQ(RunStage(activity, video).verdict, Verdict::kPass) << video;
  }
}

TEST(RealFootage, AppleIsRejectedForCameraMotion) {
  CameraMotionStage camera;
  const StageResult c = RunStage(camera, "apple.mp4");
  EXPECT_EQ(c.verdict, Verdict::kReject) << c.measurements.at("summary").dump();
  EXPECT_EQ(c.reason, "camera_motion");
  // The same clip through the shot filter: one continuous shot.
  ShotBoundaryStage shots;
  EXPECT_EQ(RunStage(shots, "apple.mp4").verdict, Verdict::kPass);
}

TEST(RealFootage, BuiltinDetectorFindsHandsOnCupsAndNoInteractionOnApple) {
  EXPECT_EQ(Analysis("02_cups.mp4").at("clip").at("detection_source"), "builtin");
  InteractionStage interaction;
  const StageResult cups = RunStage(interaction, "02_cups.mp4");
  EXPECT_EQ(cups.verdict, Verdict::kPass) << cups.measurements.at("summary").dump();
  EXPECT_GT(cups.measurements.at("summary").at("hand_fraction").get<double>(), 0.9);
  const StageResult apple = RunStage(interaction, "apple.mp4");
  EXPECT_EQ(apple.verdict, Verdict::kReject) << apple.measurements.at("summary").dump();
  EXPECT_EQ(apple.reason, "no_interaction");
}

TEST(RealFootage, VerdictStagesNeedTheAnalysis) {
  ClipContext context;
  context.clip.external_id = "c1";
  CameraMotionStage camera;
  try {
    camera.Run(context);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "missing_measurements");
    EXPECT_EQ(e.site().clip, "c1");
  }
}

}  // namespace
}  // namespace doasido::filters
