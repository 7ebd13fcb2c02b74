// The hand models only where they decide (filters/deferred_hand_models.h),
// on real footage: a clip the camera-motion verdict rejects gets the cheap
// signals it got before the learned detector existed and no hand signals
// (its hand stages record not_measured); a kept one gets
// exactly the learned signals the models in the decode gave; a clip across
// a cut gets the models on its kept shot only.
#include <gtest/gtest.h>

#include "filters/analyze.h"
#include "filters/hand_landmarker.h"
#include "filters/kept_shot.h"
#include "filters/verdict.h"
#include "stages/verdict_stages.h"
#include "test_util.h"

namespace doasido::filters {
namespace {

using namespace doasido::stages;  // the filters' queue stages

Json Analyze(const std::filesystem::path& video, std::int64_t first, std::int64_t last,
             const std::string& detector, bool deferred) {
  DecoderOptions options;
  options.first_frame = first;
  options.last_frame = last;
  AnalyzeConfig config;
  config.hand_detector = detector;
  config.learned_detector.after_cheap_verdicts = deferred;
  return AnalyzeClip(video, options, {}, config).measurements;
}

std::filesystem::path Video(const std::string& name) {
  return testing::SharedData() / "videos" / name;
}

class DeferredModels : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!HandLandmarkerAvailable(&why)) GTEST_SKIP() << why;
  }
};

TEST_F(DeferredModels, ACameraMotionRejectCostsWhatItDidWithoutTheModels) {
  // apple: the camera circles an apple (rejected for camera motion).
  const Json deferred = Analyze(Video("apple.mp4"), 0, 59, "learned", true);
  const Json builtin = Analyze(Video("apple.mp4"), 0, 59, "builtin", true);
  EXPECT_EQ(deferred.at("clip").at("detection_source"), "builtin");
  EXPECT_NE(deferred.at("clip").at("detector_note").get<std::string>().find("camera_motion"),
            std::string::npos);
  EXPECT_FALSE(deferred.contains(kHandsMeasurement));
  for (const char* section : {kShotBoundaryStageName, kCameraMotionStageName}) {
    EXPECT_EQ(deferred.at(section), builtin.at(section)) << section;
  }
  // No hand evidence: the sections the models measure are absent, named
  // under not_measured with the verdict that made them unnecessary, and
  // their stages record not_measured (never a verdict on the built-in
  // detector's boxes).
  ASSERT_TRUE(deferred.contains(kNotMeasuredKey));
  EXPECT_EQ(deferred.at(kNotMeasuredKey).at("stage"), kCameraMotionStageName);
  EXPECT_EQ(deferred.at(kNotMeasuredKey).at("measured_by"), kAnalyzeStageName);
  ClipContext context;
  context.measurements[kAnalyzeStageName] = deferred;
  for (const char* section : {kInteractionStageName, kOutOfFrameStageName, kActivityStageName}) {
    EXPECT_FALSE(deferred.contains(section)) << section;
    EXPECT_TRUE(builtin.contains(section)) << section;
  }
  const StageResult interaction = InteractionStage().Run(context);
  EXPECT_EQ(interaction.verdict, Verdict::kNotMeasured);
  EXPECT_EQ(interaction.reason, kCameraMotionStageName);
  // Re-deciding its stored measurements under any thresholds: the same.
  InteractionConfig lenient;
  lenient.min_interaction_fraction = 0;
  lenient.min_covered_fraction = 0;
  const auto again = InteractionStage(lenient).Redecide(interaction.measurements);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->verdict, Verdict::kNotMeasured);
  EXPECT_EQ(CameraMotionStage().Run(context).verdict, Verdict::kReject);
}

TEST_F(DeferredModels, AKeptClipGetsTheSignalsTheModelsInTheDecodeGave) {
  // 02_cups: a static camera, one shot, hands handling cups.
  const Json deferred = Analyze(Video("02_cups.mp4"), 0, 119, "learned", true);
  const Json in_pass = Analyze(Video("02_cups.mp4"), 0, 119, "learned", false);
  const Json builtin = Analyze(Video("02_cups.mp4"), 0, 119, "builtin", true);
  EXPECT_EQ(deferred.at("clip").at("detection_source"), "learned");
  ASSERT_TRUE(deferred.contains(kHandsMeasurement));
  // The default pair of models, named as they ran (the full palm detector,
  // the lite landmark model).
  EXPECT_EQ(deferred.at(kHandsMeasurement).at("model"),
            std::string("mediapipe_hands_") + kModelsLiteLandmark);
  const Json& samples = deferred.at(kHandsMeasurement).at("samples");
  EXPECT_EQ(samples.size(), 20u);  // every 6th of 120 frames
  for (size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ(samples[i].at("hands"), in_pass.at(kHandsMeasurement).at("samples")[i].at("hands"));
  }
  // The signals that depend on where the hands are: the learned ones.
  for (const char* section : {kInteractionStageName, kOutOfFrameStageName, kActivityStageName}) {
    EXPECT_EQ(deferred.at(section), in_pass.at(section)) << section;
  }
  // Camera motion masks the hands the built-in detector found, as before.
  EXPECT_EQ(deferred.at(kCameraMotionStageName), builtin.at(kCameraMotionStageName));
  EXPECT_EQ(deferred.at(kShotBoundaryStageName), in_pass.at(kShotBoundaryStageName));
}

TEST_F(DeferredModels, AcrossACutTheModelsSeeOnlyTheKeptShot) {
  // testvideo frames 0-179 span a cut at frame 30 (../shared/data/shots).
  const Json m = Analyze(testing::SharedData() / "shots" / "testvideo.mp4", 0, 179, "learned",
                         true);
  ClipContext context;
  context.measurements[kAnalyzeStageName] = m;
  const StageResult shot = ShotBoundaryStage().Run(context);
  context.measurements[kShotBoundaryStageName] = shot.measurements;
  const std::optional<KeptShot> kept = ReadKeptShot(shot.measurements);
  ASSERT_TRUE(kept && kept->trim) << shot.measurements.dump();
  if (shot.verdict == Verdict::kReject) {
    EXPECT_FALSE(m.contains(kHandsMeasurement));
    return;
  }
  ASSERT_TRUE(m.contains(kHandsMeasurement)) << m.at("clip").dump();
  ASSERT_FALSE(m.at(kHandsMeasurement).at("samples").empty());
  for (const Json& s : m.at(kHandsMeasurement).at("samples")) {
    EXPECT_GE(s.at("frame").get<std::int64_t>(), kept->trim->start_frame);
    EXPECT_LE(s.at("frame").get<std::int64_t>(), kept->trim->end_frame);
  }
  // Outside the kept shot no detector looked: those frames are uncovered.
  const std::vector<int> covered = IntArray(m.at(kInteractionStageName), "covered");
  for (std::int64_t i = 0; i < kept->trim->start_frame; ++i) EXPECT_EQ(covered[i], 0) << i;
}

}  // namespace
}  // namespace doasido::filters
