// Sampling that follows the motion (LearnedDetectorConfig::still_sample_fps,
// filters/learned_hand_detector.h), on real footage against its labels
// (../shared/data/README.md): with the default thinning every filter that
// reads the hands gives the labelled verdict and the verdict the models on
// every sample give; a still sample repeats the hands of a sample the models
// saw at most 1 / still_sample_fps earlier; where a scene stands still the
// models see fewer samples. And the new options are checked at config load.
#include <gtest/gtest.h>

#include "core/error.h"
#include "filters/activity.h"
#include "filters/analyze.h"
#include "filters/hand_landmarker.h"
#include "filters/interaction.h"
#include "filters/learned_hand_detector.h"
#include "filters/out_of_frame.h"
#include "filters/verdict.h"
#include "stages/verdict_stages.h"
#include "test_util.h"

namespace doasido::filters {
namespace {

using namespace doasido::stages;  // the filters' queue stages

Json Analyze(const std::string& video, bool thinned) {
  AnalyzeConfig config;
  config.hand_detector = "learned";
  // The models on every clip, so the verdicts that read the hands are seen
  // on the negatives too (the default defers them: filters_deferred_models_test).
  config.learned_detector.after_cheap_verdicts = false;
  if (!thinned) {
    config.learned_detector.still_sample_fps = config.learned_detector.sample_fps;
    config.learned_detector.no_hand_palm_every = 1;  // the palm gate off too
  }
  return AnalyzeClip(testing::SharedData() / "videos" / video, DecoderOptions{}, {}, config)
      .measurements;
}

StageResult Judge(stages::Stage& stage, const Json& analysis) {
  ClipContext context;
  context.measurements[kAnalyzeStageName] = analysis;
  return stage.Run(context);
}

class MotionSampling : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!HandLandmarkerAvailable(&why)) GTEST_SKIP() << why;
  }
};

TEST_F(MotionSampling, ThinnedSamplingKeepsTheLabelledVerdicts) {
  struct Labelled {
    const char* video;
    bool positive;  // else the interaction filter must reject it
  };
  // yoga: a still room with a person far away (hands, no object handled);
  // asl_hand: one hand signing in the air; 02_cups and laptop_trackpad:
  // hands handle objects in front of a static camera.
  for (const Labelled l : {Labelled{"yoga.mp4", false}, Labelled{"asl_hand.mp4", false},
                           Labelled{"02_cups.mp4", true}, Labelled{"laptop_trackpad.mp4", true}}) {
    const Json thinned = Analyze(l.video, true);
    const Json full = Analyze(l.video, false);
    InteractionStage interaction;
    OutOfFrameStage out_of_frame;
    ActivityStage activity;
    for (stages::Stage* stage : std::initializer_list<stages::Stage*>{&interaction, &out_of_frame, &activity}) {
      const StageResult a = Judge(*stage, thinned), b = Judge(*stage, full);
      EXPECT_EQ(a.verdict, b.verdict) << l.video << " " << stage->Name();
      EXPECT_EQ(a.reason, b.reason) << l.video << " " << stage->Name();
    }
    const StageResult i = Judge(interaction, thinned);
    if (l.positive) {
      EXPECT_EQ(i.verdict, Verdict::kPass) << l.video;
      EXPECT_EQ(Judge(activity, thinned).verdict, Verdict::kPass) << l.video;
    } else {
      EXPECT_EQ(i.verdict, Verdict::kReject) << l.video;
      EXPECT_EQ(i.reason, "no_interaction") << l.video;
    }

    // Every sample of the full rate ran the models.
    const Json& all = full.at(kHandsMeasurement);
    EXPECT_EQ(all.at("model_samples").get<std::size_t>(), all.at("samples").size()) << l.video;
    // A still sample repeats a modelled sample at most a second back
    // (still_sample_fps = 1).
    const Json& hands = thinned.at(kHandsMeasurement);
    ASSERT_EQ(hands.at("samples").size(), all.at("samples").size()) << l.video;
    const double fps = thinned.at("clip").at("fps").get<double>();
    std::map<std::int64_t, Json> modelled;
    int held = 0, gated = 0;
    for (const Json& s : hands.at("samples")) {
      const std::int64_t frame = s.at("frame").get<std::int64_t>();
      if (s.contains("palm_gated")) {
        // The palm gate kept the palm detector from a hand-less sample.
        ++gated;
        EXPECT_TRUE(s.at("hands").empty()) << l.video << " frame " << frame;
        EXPECT_EQ(s.at("ms").get<double>(), 0.0);
        continue;
      }
      if (!s.contains("held_from")) {
        modelled[frame] = s.at("hands");
        continue;
      }
      ++held;
      const std::int64_t from = s.at("held_from").get<std::int64_t>();
      ASSERT_TRUE(modelled.count(from)) << l.video << " frame " << frame;
      EXPECT_EQ(s.at("hands"), modelled.at(from)) << l.video << " frame " << frame;
      EXPECT_GT(frame, from);
      EXPECT_LT(frame - from, fps * 1.0 + 1) << l.video << " frame " << frame;
      EXPECT_EQ(s.at("ms").get<double>(), 0.0);
    }
    EXPECT_EQ(gated, hands.at("palm_gated").get<int>()) << l.video;
    EXPECT_EQ(held + gated + hands.at("model_samples").get<int>(),
              static_cast<int>(hands.at("samples").size()));
    // yoga's room stands still: most of its samples need no model run
    // (held, or kept from the palm detector by the palm gate: no hand is
    // tracked there).
    if (std::string(l.video) == "yoga.mp4") {
      EXPECT_GT(held + gated, static_cast<int>(hands.at("samples").size()) / 3) << held;
    }
  }
}

// The palm gate on frames with no hand: the palm detector looks at the
// first, then at most every 3rd, and never where nothing changed since it
// last looked (a gray square standing in for a hand coming in).
TEST(PalmGate, LooksEveryThirdHandlessFrameAndOnlyWhereTheFrameChanged) {
  PalmGate gate(3, 0.01, ActivitySignalConfig{});
  const cv::Mat empty(120, 160, CV_8U, cv::Scalar(40));
  cv::Mat hand = empty.clone();
  hand(cv::Rect(60, 40, 30, 30)).setTo(200);  // 900 of 19,200 pixels: 4.7 %
  EXPECT_TRUE(gate.Look(empty));  // nothing to compare with
  for (int i = 0; i < 6; ++i) EXPECT_FALSE(gate.Look(empty)) << i;  // nothing changed
  EXPECT_TRUE(gate.Look(hand));   // changed, 7 frames since
  EXPECT_FALSE(gate.Look(empty));  // changed back, but 1 frame since
  EXPECT_FALSE(gate.Look(empty));  // 2 frames
  EXPECT_TRUE(gate.Look(empty));   // 3 frames, and it differs from the square
  gate.Reset();
  EXPECT_TRUE(gate.Look(empty));
  PalmGate every(1, 0, ActivitySignalConfig{});  // off: every frame
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(every.Look(empty)) << i;
}

TEST(MotionSamplingConfig, BadValuesAreRefusedAtLoad) {
  const auto refused = [](LearnedDetectorConfig c, const std::string& field) {
    try {
      CheckConfig(c, "filters_analyze.learned_detector");
      ADD_FAILURE() << field << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "bad_config");
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  LearnedDetectorConfig c;
  CheckConfig(c, "filters_analyze.learned_detector");  // the defaults are valid
  c.still_sample_fps = 10;  // above sample_fps (5)
  refused(c, "still_sample_fps");
  c = {};
  c.still_sample_fps = 0;
  refused(c, "still_sample_fps");
  c = {};
  c.still_changed_fraction = 1.5;
  refused(c, "still_changed_fraction");
  c = {};
  c.palm_every = 0;
  refused(c, "palm_every");
  c = {};
  c.no_hand_palm_every = 0;
  refused(c, "no_hand_palm_every");
  c = {};
  c.no_hand_changed_fraction = -0.1;
  refused(c, "no_hand_changed_fraction");
  // Thinning off (the rate where nothing moves is the sampling rate) is valid.
  c = {};
  c.still_sample_fps = c.sample_fps;
  CheckConfig(c, "filters_analyze.learned_detector");
}

}  // namespace
}  // namespace doasido::filters
