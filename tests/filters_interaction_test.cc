// The external-detector seam (a command writing 100DOH-format detections per
// frame) and the interaction decision on its boxes.
#include <gtest/gtest.h>

#include <string>

#include "core/error.h"
#include "filters/interaction.h"
#include "stages/detector_stage.h"
#include "stages/verdict_stages.h"
#include "synth/generator.h"
#include "tests/test_util.h"

namespace doasido::filters {
namespace {

using namespace doasido::stages;  // the filters' queue stages

// A detector "command" that writes two frames of output, as a user's wrapper
// around 100DOH's hand_object_detector would.
std::string FakeDetector() {
  return "printf '%s\\n' "
         "'{\"frame\": 3, \"hand_dets\": [[10,20,110,220,0.9,3,0.6,0.8,40,1]], "
         "\"obj_dets\": [[100,50,200,150,0.8]]}' "
         "'{\"frame\": 18, \"hand_dets\": [[12,20,112,220,0.2,0,0,0,0,0]], \"obj_dets\": []}' "
         "> {output}";
}

TEST(ExternalDetector, ReadsHandsAndObjectsAndDropsLowScores) {
  testing::TempDir dir;
  ExternalDetectorConfig config{.command = FakeDetector(), .min_score = 0.5};
  const auto d = RunExternalDetector(config, testing::SharedData() / "videos" / "02_cups.mp4", 0,
                                     -1, dir / "out.jsonl", "clip-1");
  ASSERT_EQ(d.size(), 2u);  // the 0.2 hand of frame 18 is dropped
  EXPECT_EQ(d[0].frame, 3);
  EXPECT_EQ(d[0].kind, "hand");
  EXPECT_DOUBLE_EQ(d[0].x1, 10);
  EXPECT_DOUBLE_EQ(d[0].y2, 220);
  EXPECT_DOUBLE_EQ(d[0].score, 0.9);
  EXPECT_EQ(d[0].contact_state, 3);
  EXPECT_DOUBLE_EQ(d[0].dx, 0.6);
  EXPECT_DOUBLE_EQ(d[0].dy, 0.8);
  EXPECT_DOUBLE_EQ(d[0].magnitude, 40);
  EXPECT_EQ(d[0].hand_side, 1);
  EXPECT_EQ(d[0].source, "detector:external");
  EXPECT_EQ(d[1].kind, "object");
  EXPECT_DOUBLE_EQ(d[1].x2, 200);
}

TEST(ExternalDetector, SubstitutesQuotedArguments) {
  testing::TempDir dir;
  // Echo the substituted values back as a frame number and a box.
  ExternalDetectorConfig config{
      .command =
          "printf '{\"frame\": %s, \"hand_dets\": [[%s,0,500,10,1,3,0,0,0,0]]}\\n' "
          "{first_frame} {last_frame} > {output}"};
  const auto d =
      RunExternalDetector(config, "/no/such dir/it's.mp4", 42, 99, dir / "out put.jsonl", "c");
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].frame, 42);
  EXPECT_DOUBLE_EQ(d[0].x1, 99);
}

TEST(ExternalDetector, FailuresNameTheClipAndTheLine) {
  testing::TempDir dir;
  try {
    RunExternalDetector({.command = "exit 3"}, "/v.mp4", 0, -1, dir / "o.jsonl", "clip-9");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "detector_failed");
    EXPECT_EQ(e.site().clip, "clip-9");
  }
  try {
    RunExternalDetector({.command = "true"}, "/v.mp4", 0, -1, dir / "o.jsonl", "clip-9");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "detector_failed");  // no output file
  }
  testing::WriteFile(
      dir / "bad.jsonl",
      "{\"frame\": 1, \"hand_dets\": []}\n{\"frame\": 2, \"hand_dets\": [[1,2,3]]}\n");
  try {
    ReadDetectorOutput(dir / "bad.jsonl", 0.5, "x");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_detections");
    EXPECT_EQ(e.site().line, 2);
    EXPECT_EQ(e.site().field, "hand_dets");
  }
}

TEST(ExternalDetectorStage, RunsOnTheClipAndStoresItsOutput) {
  testing::TempDir dir;
  ClipContext context;
  context.clip.id = 5;
  context.video.path = (testing::SharedData() / "videos" / "02_cups.mp4").string();
  context.artifact_dir = dir / "artifacts";
  ExternalDetectorStage none;
  StageResult r = none.Run(context);
  EXPECT_EQ(r.verdict, Verdict::kPass);
  EXPECT_EQ(r.reason, "no_detector");
  EXPECT_TRUE(r.detections.empty());

  ExternalDetectorStage stage({.command = FakeDetector()});
  r = stage.Run(context);
  EXPECT_EQ(r.detections.size(), 2u);
  EXPECT_EQ(r.measurements.at("frames").get<int>(), 1);
  ASSERT_EQ(r.artifacts.size(), 1u);
  EXPECT_TRUE(std::filesystem::exists(context.artifact_dir / r.artifacts[0].second));
}

TEST(Interaction, ContactStatesDecide) {
  InteractionSignals s;
  // 10 covered frames: 3 with a hand holding a portable object (bit 3),
  // 5 with a hand touching furniture (bit 4), 2 with no hand.
  for (int i = 0; i < 10; ++i) {
    s.covered.push_back(1);
    s.hands.push_back(i < 8 ? 1 : 0);
    s.objects.push_back(i < 3 ? 1 : 0);
    s.contact.push_back(i < 3 ? 1 << 3 : i < 8 ? 1 << 4 : 0);
  }
  EXPECT_DOUBLE_EQ(InteractionFraction(s, {3}, 0, 9), 0.3);
  EXPECT_DOUBLE_EQ(InteractionFraction(s, {3, 4}, 0, 9), 0.8);
  EXPECT_DOUBLE_EQ(InteractionFraction(s, {3}, 3, 9), 0.0);  // a trimmed span
  const Json m = {{"clip", {{"first_frame", 0}, {"frames", 10}}}, {"signals", ToJson(s)}};
  InteractionStage strict({.contact_states = {3}, .min_interaction_fraction = 0.5});
  EXPECT_EQ(strict.Redecide(m)->verdict, Verdict::kReject);
  EXPECT_EQ(strict.Redecide(m)->reason, "no_interaction");
  InteractionStage any({.contact_states = {3, 4}, .min_interaction_fraction = 0.5});
  EXPECT_EQ(any.Redecide(m)->verdict, Verdict::kPass);
}

// A rendered handover clip (synth: the right hand picks the object up, the
// left takes it over): from its 100DOH-style boxes the extractor counts the
// hands touching the object in every frame, as the clip's ground truth
// (contact flags of the visible hands) has it, and the stage's summary says
// in what share of the frames both hands hold it.
TEST(Interaction, CountsTheHandsInContactOnATwoHandClip) {
  synth::SynthConfig cfg;
  cfg.width = 160;
  cfg.height = 120;
  cfg.frames = 48;
  cfg.seed = 5;
  cfg.two_hand_task = "handover";
  const synth::RenderedClip clip = synth::RenderClip(cfg, 0, synth::DefectKind::kClean);
  InteractionExtractor extractor;
  int expected_both = 0;
  std::vector<int> expected;
  for (int t = 0; t < cfg.frames; ++t) {
    FrameContext context;
    context.boxes.known = true;
    for (const synth::VocHand& h : clip.voc[t].hands) {
      context.boxes.hands.emplace_back(h.box.x0, h.box.y0, h.box.x1 - h.box.x0 + 1, h.box.y1 - h.box.y0 + 1);
      context.boxes.hand_contact.push_back(h.contact_state);
    }
    for (const synth::VocObject& o : clip.voc[t].objects) {
      context.boxes.objects.emplace_back(o.box.x0, o.box.y0, o.box.x1 - o.box.x0 + 1, o.box.y1 - o.box.y0 + 1);
    }
    extractor.Consume(context);
    const Json& facts = clip.gt.at("per_frame").at(t);
    int touching = 0;
    for (int side = 0; side < 2; ++side) {
      touching += facts.at("contact")[side].get<bool>() && facts.at("hand_pixels")[side].get<int>() > 0;
    }
    expected.push_back(touching);
    expected_both += touching == 2;
  }
  EXPECT_EQ(extractor.signals().in_contact, expected);
  std::printf("handover clip: hands in contact per frame:");
  for (int n : expected) std::printf(" %d", n);
  std::printf("\n");
  EXPECT_GT(expected_both, 0);
  EXPECT_GT(std::count(expected.begin(), expected.end(), 1), 0);
  const Json m = {{"clip", {{"first_frame", 0}, {"frames", cfg.frames}}}, {"signals", ToJson(extractor.signals())}};
  const auto decided = InteractionStage().Redecide(m);
  ASSERT_TRUE(decided.has_value());
  EXPECT_DOUBLE_EQ(decided->measurements.at("summary").at("two_hand_fraction").get<double>(),
                   double(expected_both) / cfg.frames);
  EXPECT_EQ(decided->verdict, Verdict::kPass);
  // An analysis stored before hands in contact were counted still decides.
  Json old = m;
  old["signals"].erase("in_contact");
  EXPECT_TRUE(InteractionStage().Redecide(old)->measurements.at("summary").at("two_hand_fraction").is_null());
}

}  // namespace
}  // namespace doasido::filters
