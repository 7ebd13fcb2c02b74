// Re-thresholding: every verdict stage re-decides from its own stored
// measurements, consistently with the stored signals, without decoding.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <set>
#include <string>

#include "filters/analyze.h"
#include "filters/verdict.h"
#include "stages/verdict_stages.h"
#include "test_util.h"

namespace doasido::filters {
namespace {

using namespace doasido::stages;  // the filters' queue stages

const Json& Analysis(const std::string& path) {
  static std::map<std::string, Json> cache;
  auto it = cache.find(path);
  if (it == cache.end()) {
    ClipAnalysis a = AnalyzeClip(testing::SharedData() / path, DecoderOptions{}, {}, {});
    it = cache.emplace(path, std::move(a.measurements)).first;
  }
  return it->second;
}

StageResult RunOn(stages::Stage& stage, const Json& analysis) {
  ClipContext context;
  context.measurements[kAnalyzeStageName] = analysis;
  return stage.Run(context);
}

std::vector<std::int64_t> Golden(const std::string& name) {
  std::ifstream in(testing::SharedData() / "shots" / "goldens" / name);
  return Json::parse(in).at("cuts").get<std::vector<std::int64_t>>();
}

TEST(Redecide, SameConfigGivesTheSameVerdict) {
  const Json& analysis = Analysis("shots/testvideo.mp4");
  ShotBoundaryStage shots;
  ActivityStage activity;
  CameraMotionStage camera;
  OutOfFrameStage out;
  InteractionStage interaction;
  for (stages::Stage* stage :
       std::initializer_list<stages::Stage*>{&shots, &activity, &camera, &out, &interaction}) {
    const StageResult run = RunOn(*stage, analysis);
    const std::optional<StageResult> again = stage->Redecide(run.measurements);
    ASSERT_TRUE(again.has_value()) << stage->Name();
    EXPECT_EQ(again->verdict, run.verdict) << stage->Name();
    EXPECT_EQ(again->reason, run.reason) << stage->Name();
    EXPECT_EQ(again->measurements, run.measurements) << stage->Name();
  }
}

TEST(Redecide, ShotPolicyTrimsToTheLongestSegmentOfTheGoldenCuts) {
  const Json& analysis = Analysis("shots/testvideo.mp4");
  ShotBoundaryConfig adaptive;
  adaptive.boundary_detectors = {"adaptive"};
  ShotBoundaryStage shots(adaptive);
  const StageResult r = RunOn(shots, analysis);
  // Expected from PySceneDetect's goldens: the AdaptiveDetector's cuts.
  std::set<std::int64_t> cuts;
  for (auto c : Golden("testvideo.mp4.AdaptiveDetector.default.json")) cuts.insert(c);
  std::int64_t start = 0, best_start = 0, best_end = 0;
  cuts.insert(720);
  for (auto c : cuts) {
    if (c - start > best_end - best_start) {
      best_start = start;
      best_end = c;
    }
    start = c;
  }
  EXPECT_EQ(r.verdict, Verdict::kPass);
  EXPECT_EQ(r.reason, "trimmed");
  EXPECT_EQ(r.measurements.at("summary").at("trim").at("start_frame").get<std::int64_t>(),
            best_start);
  EXPECT_EQ(r.measurements.at("summary").at("trim").at("end_frame").get<std::int64_t>(),
            best_end - 1);

  // Demand longer segments than the longest: the clip spans a boundary.
  ShotBoundaryConfig strict = adaptive;
  strict.min_segment_s = (best_end - best_start) / (30000.0 / 1001.0) + 0.1;
  const std::optional<StageResult> rejected = ShotBoundaryStage(strict).Redecide(r.measurements);
  EXPECT_EQ(rejected->verdict, Verdict::kReject);
  EXPECT_EQ(rejected->reason, "shot_boundary");

  // Re-threshold the content score above every stored score: no cut left.
  ShotBoundaryConfig lax;
  lax.boundary_detectors = {"content"};
  const auto& s = analysis.at("shot_boundary");
  double max_score = 0;
  for (size_t i = 0; i < s.at("delta_hue").size(); ++i) {
    max_score = std::max(max_score,
                         (s.at("delta_hue")[i].get<double>() + s.at("delta_sat")[i].get<double>() +
                          s.at("delta_lum")[i].get<double>()) /
                             3.0);
  }
  lax.content_threshold = max_score + 1e-6;
  const std::optional<StageResult> none = ShotBoundaryStage(lax).Redecide(r.measurements);
  EXPECT_EQ(none->verdict, Verdict::kPass);
  EXPECT_EQ(none->reason, "");
  EXPECT_TRUE(none->measurements.at("summary").at("boundaries").empty());
  // ... and exactly at the largest score the frame holding it is a cut again.
  lax.content_threshold = max_score;
  EXPECT_FALSE(ShotBoundaryStage(lax)
                   .Redecide(r.measurements)
                   ->measurements.at("summary")
                   .at("boundaries")
                   .empty());
}

TEST(Redecide, FadeDetectorTrimsDarkEnds) {
  // testvideo.mp4 fades in from black and out to black (its goldens'
  // ThresholdDetector cuts start at 15): the default policy also cuts where
  // the leading dark frames end and the trailing ones begin.
  const Json& analysis = Analysis("shots/testvideo.mp4");
  const auto mean = analysis.at("shot_boundary").at("mean_intensity").get<std::vector<double>>();
  std::int64_t lead = 0, tail = static_cast<std::int64_t>(mean.size());
  while (mean[lead] < 12) ++lead;
  while (mean[tail - 1] < 12) --tail;
  ASSERT_GT(lead, 0);
  ASSERT_LT(tail, static_cast<std::int64_t>(mean.size()));
  ShotBoundaryConfig fades;
  fades.boundary_detectors = {"fade"};
  const StageResult r = RunOn(*std::make_unique<ShotBoundaryStage>(fades), analysis);
  std::set<std::int64_t> expected = {lead, tail};
  for (auto c : Golden("testvideo.mp4.ThresholdDetector.default.json")) expected.insert(c);
  const auto got = r.measurements.at("summary").at("boundaries").get<std::set<std::int64_t>>();
  EXPECT_EQ(got, expected);
}

TEST(Redecide, CameraMotionBandsFollowTheStoredRates) {
  const Json& analysis = Analysis("videos/apple.mp4");
  CameraMotionStage stage;
  const StageResult r = RunOn(stage, analysis);
  ASSERT_EQ(r.verdict, Verdict::kReject);
  const Json& m = r.measurements.at("summary");
  const double t = m.at("translation_rate"), rot = m.at("rotation_rate"), sc = m.at("scale_rate");
  // Every reject level just above what was measured, the flag level for
  // translation just below it: flag.
  CameraMotionConfig c;
  c.reject_translation_rate = t * 1.01;
  c.reject_rotation_rate = rot * 1.01;
  c.reject_scale_rate = sc * 1.01;
  c.reject_peak_translation_rate = m.at("peak_translation_rate").get<double>() * 1.01;
  c.reject_peak_rotation_rate = m.at("peak_rotation_rate").get<double>() * 1.01;
  c.reject_peak_scale_rate = m.at("peak_scale_rate").get<double>() * 1.01;
  c.flag_translation_rate = t * 0.99;
  c.flag_rotation_rate = rot * 1.01;
  c.flag_scale_rate = sc * 1.01;
  std::optional<StageResult> d = CameraMotionStage(c).Redecide(r.measurements);
  EXPECT_EQ(d->verdict, Verdict::kFlag);
  EXPECT_EQ(d->reason, "camera_motion");
  // Flag level above too: pass.
  c.flag_translation_rate = t * 1.01;
  d = CameraMotionStage(c).Redecide(r.measurements);
  EXPECT_EQ(d->verdict, Verdict::kPass);
  // Reject level exactly at the measured rotation rate: reject (inclusive).
  c.reject_rotation_rate = rot;
  d = CameraMotionStage(c).Redecide(r.measurements);
  EXPECT_EQ(d->verdict, Verdict::kReject);
}

TEST(Redecide, ActivityThresholdFollowsTheStoredFraction) {
  const Json& analysis = Analysis("videos/02_cups.mp4");
  ActivityStage stage;
  const StageResult r = RunOn(stage, analysis);
  const double active = r.measurements.at("summary").at("active_fraction");
  ASSERT_GT(active, 0.5);
  ActivityConfig c;
  c.min_active_fraction = active;
  EXPECT_EQ(ActivityStage(c).Redecide(r.measurements)->verdict, Verdict::kPass);
  c.min_active_fraction = std::nextafter(active, 2.0);
  const auto d = ActivityStage(c).Redecide(r.measurements);
  EXPECT_EQ(d->verdict, Verdict::kReject);
  EXPECT_EQ(d->reason, "no_activity");
  // Raising the per-frame bar above every stored moving fraction leaves no
  // active frame at all.
  c = ActivityConfig{};
  c.min_moving_fraction = 1.01;
  EXPECT_EQ(ActivityStage(c).Redecide(r.measurements)->verdict, Verdict::kReject);
}

// Detections given to the analysis (instead of the built-in detector).
std::vector<Detection> Boxes(double hand_x1, int contact, bool with_object) {
  std::vector<Detection> out;
  for (std::int64_t f = 0; f < 300; f += 15) {  // sparse, like 100DOH annotations
    Detection h;
    h.frame = f;
    h.kind = "hand";
    h.x1 = hand_x1;
    h.y1 = 300;
    h.x2 = hand_x1 + 200;
    h.y2 = 500;
    h.contact_state = contact;
    h.source = "test";
    out.push_back(h);
    if (with_object) {
      Detection o = h;
      o.kind = "object";
      o.x1 = hand_x1 + 150;
      o.x2 = hand_x1 + 350;
      o.contact_state = -1;
      out.push_back(o);
    }
  }
  return out;
}

TEST(Redecide, InteractionAndOutOfFrameFromGivenDetections) {
  const auto video = testing::SharedData() / "videos" / "02_cups.mp4";
  ClipAnalysis inside = AnalyzeClip(video, {}, Boxes(500, 3, true), {});
  EXPECT_EQ(inside.measurements.at("clip").at("detection_source"), "clip");
  EXPECT_TRUE(inside.builtin_detections.empty());
  InteractionStage interaction;
  OutOfFrameStage out;
  StageResult i = RunOn(interaction, inside.measurements);
  EXPECT_EQ(i.verdict, Verdict::kPass);
  EXPECT_DOUBLE_EQ(i.measurements.at("summary").at("interaction_fraction").get<double>(), 1.0);
  StageResult o = RunOn(out, inside.measurements);
  EXPECT_EQ(o.verdict, Verdict::kPass);
  EXPECT_DOUBLE_EQ(o.measurements.at("summary").at("out_fraction").get<double>(), 0.0);

  // Contact state N (no contact): no interaction; counting "none" as
  // interaction on re-decision flips it back.
  ClipAnalysis idle = AnalyzeClip(video, {}, Boxes(500, 0, false), {});
  i = RunOn(interaction, idle.measurements);
  EXPECT_EQ(i.verdict, Verdict::kReject);
  EXPECT_EQ(i.reason, "no_interaction");
  InteractionConfig any;
  any.contact_states = {0, 3};
  EXPECT_EQ(InteractionStage(any).Redecide(i.measurements)->verdict, Verdict::kPass);

  // The hand box at the left border in every frame: flagged by default, and
  // rejected once cut frames are allowed to reject.
  ClipAnalysis cut = AnalyzeClip(video, {}, Boxes(0, 3, true), {});
  o = RunOn(out, cut.measurements);
  EXPECT_EQ(o.verdict, Verdict::kFlag);
  EXPECT_EQ(o.reason, "out_of_frame");
  EXPECT_DOUBLE_EQ(o.measurements.at("summary").at("hand_cut_fraction").get<double>(), 1.0);
  OutOfFrameConfig strict;
  strict.reject_cut_fraction = 0.9;
  EXPECT_EQ(OutOfFrameStage(strict).Redecide(o.measurements)->verdict, Verdict::kReject);
  OutOfFrameConfig tolerant;
  tolerant.flag_cut_fraction = 1.01;
  EXPECT_EQ(OutOfFrameStage(tolerant).Redecide(o.measurements)->verdict, Verdict::kPass);

  // The hand leaves the picture from frame 150 on (only the object is
  // annotated there): half the frames miss the hand.
  std::vector<Detection> leaving;
  for (const Detection& d : Boxes(500, 3, true)) {
    if (d.kind == "object" || d.frame < 150) leaving.push_back(d);
  }
  ClipAnalysis gone = AnalyzeClip(video, {}, leaving, {});
  o = RunOn(out, gone.measurements);
  EXPECT_EQ(o.verdict, Verdict::kReject);
  EXPECT_EQ(o.reason, "out_of_frame");
  EXPECT_EQ(o.measurements.at("summary").at("expected_hands").get<int>(), 1);
  // Frames 143..299 take the boxes of annotations 150..285 (hand gone).
  EXPECT_NEAR(o.measurements.at("summary").at("hand_missing_fraction").get<double>(), 157.0 / 300.0,
              1e-9);
}

TEST(DissolveCuts, OneCutPerShortBurstNoneForALongOne) {
  std::vector<double> changed(200, 0.05);
  for (int i = 60; i < 72; ++i) changed[i] = 0.8;  // most pixels changed for 12 frames
  changed[66] = 0.9;
  EXPECT_EQ(DissolveCuts(changed, 15, 0.5, 0.3, 15), std::vector<std::int64_t>{66 - 7});
  for (int i = 100; i < 150; ++i) changed[i] = 0.7;  // 50 frames: a scene that keeps changing
  EXPECT_EQ(DissolveCuts(changed, 15, 0.5, 0.3, 15), std::vector<std::int64_t>{59});
  // Below the threshold nothing is a dissolve.
  EXPECT_TRUE(DissolveCuts(changed, 15, 0.95, 0.3, 15).empty());
}

}  // namespace
}  // namespace doasido::filters
