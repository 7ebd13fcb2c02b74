// Dissolve detection by the linear-blend test, on clips built in the test:
// two different drawn scenes cross-faded over 10 frames must give one cut
// inside the cross-fade; motion and a hard cut must give none.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "filters/analyze.h"
#include "filters/shot_boundary.h"
#include "test_util.h"

namespace doasido::filters {
namespace {

constexpr int kWidth = 160, kHeight = 120;

// Scene A with a small disc (a "hand") at horizontal position x.
cv::Mat SceneA(int x) {
  cv::Mat img(kHeight, kWidth, CV_8UC3, cv::Scalar(60, 70, 80));
  cv::rectangle(img, {10, 60, 60, 50}, cv::Scalar(30, 160, 220), cv::FILLED);
  cv::line(img, {0, 20}, {kWidth, 50}, cv::Scalar(240, 240, 240), 3);
  cv::circle(img, {x, 30}, 8, cv::Scalar(150, 120, 200), cv::FILLED);
  return img;
}

// Scene B: a different drawing, with its own moving disc.
cv::Mat SceneB(int x) {
  cv::Mat img(kHeight, kWidth, CV_8UC3, cv::Scalar(200, 190, 170));
  cv::ellipse(img, {110, 70}, {40, 25}, 30, 0, 360, cv::Scalar(20, 40, 90), cv::FILLED);
  cv::rectangle(img, {5, 5, 50, 40}, cv::Scalar(90, 200, 60), cv::FILLED);
  cv::circle(img, {x, 100}, 8, cv::Scalar(40, 40, 40), cv::FILLED);
  return img;
}

ShotSignals Analyse(const std::vector<cv::Mat>& frames) {
  ShotSignalExtractor extractor;
  VideoGeometry geometry;
  geometry.width = geometry.full_width = kWidth;
  geometry.height = geometry.full_height = kHeight;
  geometry.fps = 30;
  extractor.Begin(geometry);
  AnalysisFrame frame;
  FrameContext context;
  for (size_t i = 0; i < frames.size(); ++i) {
    frame.index = static_cast<std::int64_t>(i);
    frame.bgr = frames[i];
    context.frame = &frame;
    context.ordinal = frame.index;
    cv::cvtColor(frame.bgr, context.gray, cv::COLOR_BGR2GRAY);
    extractor.Consume(context);
  }
  extractor.Finish();
  return extractor.signals();
}

std::vector<std::int64_t> Blends(const ShotSignals& s) {
  const ShotBoundaryConfig c;
  return BlendCuts(s.blend_changed, s.blend_unexplained, s.blend_step, c.blend_min_changed,
                   c.blend_max_unexplained, c.blend_min_run, c.min_scene_len);
}

TEST(BlendCuts, CrossFadeOverTenFramesGivesOneCutInside) {
  // 30 frames of A, a cross-fade over frames 30..39 (weight of B (i+1)/11,
  // as synth/ renders it), then 30 frames of B; the discs keep moving.
  constexpr int kStart = 30, kFrames = 10;
  std::vector<cv::Mat> frames;
  for (int t = 0; t < 70; ++t) {
    const int x = 20 + t;
    if (t < kStart) {
      frames.push_back(SceneA(x));
    } else if (t < kStart + kFrames) {
      const double w = static_cast<double>(t - kStart + 1) / (kFrames + 1);
      cv::Mat blend;
      cv::addWeighted(SceneA(x), 1.0 - w, SceneB(x), w, 0.0, blend);
      frames.push_back(blend);
    } else {
      frames.push_back(SceneB(x));
    }
  }
  const ShotSignals s = Analyse(frames);
  ASSERT_EQ(s.blend_changed.size(), frames.size());
  const std::vector<std::int64_t> cuts = Blends(s);
  ASSERT_EQ(cuts.size(), 1u);
  EXPECT_GE(cuts[0], kStart);
  EXPECT_LT(cuts[0], kStart + kFrames);
  // The "dissolve" detector (both tests merged) reports it once, at most a
  // few frames early (the changed-fraction test places it by its peak).
  const std::vector<std::int64_t> dissolves = CutsOf("dissolve", s, ShotBoundaryConfig{});
  ASSERT_EQ(dissolves.size(), 1u);
  EXPECT_GE(dissolves[0], kStart - 3);
  EXPECT_LT(dissolves[0], kStart + kFrames);
}

TEST(BlendCuts, MotionAndAHardCutAreNoDissolve) {
  // A large block sweeping across scene A (it changes far more than 0.2 of
  // the pixels over 6 frames), then a hard cut to B.
  std::vector<cv::Mat> frames;
  for (int t = 0; t < 60; ++t) {
    if (t < 40) {
      cv::Mat img = SceneA(20 + t);
      cv::rectangle(img, {t * 3 - 40, 20, 70, 90}, cv::Scalar(210, 180, 160), cv::FILLED);
      frames.push_back(img);
    } else {
      frames.push_back(SceneB(20 + t));
    }
  }
  const ShotSignals s = Analyse(frames);
  double max_changed = 0;
  for (double v : s.blend_changed) max_changed = std::max(max_changed, v);
  EXPECT_GT(max_changed, ShotBoundaryConfig{}.blend_min_changed);  // the test is not vacuous
  EXPECT_TRUE(Blends(s).empty());
}

TEST(BlendCuts, RunsShorterThanMinRunAndCloseCutsAreDropped) {
  // Entries describe frame t - step (step 3 here).
  std::vector<double> changed(60, 0.5), unexplained(60, 0.9);
  for (int t = 20; t < 22; ++t) unexplained[t] = 0.1;  // run of 2 < min_run 3
  EXPECT_TRUE(BlendCuts(changed, unexplained, 3, 0.2, 0.4, 3, 15).empty());
  for (int t = 20; t < 26; ++t) unexplained[t] = 0.1;  // run 20..25: cut (20+25)/2-3 = 19
  for (int t = 28; t < 31; ++t) unexplained[t] = 0.1;  // cut 26: too close to 19
  for (int t = 50; t < 53; ++t) unexplained[t] = 0.1;  // cut 48
  EXPECT_EQ(BlendCuts(changed, unexplained, 3, 0.2, 0.4, 3, 15),
            (std::vector<std::int64_t>{19, 48}));
  // Too little of the picture changed: no dissolve.
  EXPECT_TRUE(BlendCuts(changed, unexplained, 3, 0.6, 0.4, 3, 15).empty());
  EXPECT_TRUE(BlendCuts({}, {}, 3, 0.2, 0.4, 3, 15).empty());
}

TEST(BlendCuts, NoDissolveInRealFootageWithoutOne) {
  // Close-up hands (02_cups, 03_blocks), people jumping (bedroom) and a
  // circling camera (apple) change much of the picture, none by a dissolve.
  for (const std::string name : {"02_cups", "03_blocks", "bedroom", "apple"}) {
    const ClipAnalysis a =
        AnalyzeClip(testing::SharedData() / "videos" / (name + ".mp4"), DecoderOptions{}, {}, {});
    const ShotSignals s = ShotSignalsFromJson(a.measurements.at("shot_boundary"));
    ASSERT_EQ(s.blend_changed.size(), s.delta_hue.size()) << name;
    double least_unexplained = 1;
    for (size_t t = 0; t < s.blend_changed.size(); ++t) {
      if (s.blend_changed[t] >= ShotBoundaryConfig{}.blend_min_changed) {
        least_unexplained = std::min(least_unexplained, s.blend_unexplained[t]);
      }
    }
    std::printf("%s: least unexplained fraction where >= 0.2 changed: %.3f\n", name.c_str(),
                least_unexplained);
    EXPECT_TRUE(Blends(s).empty()) << name;
  }
}

}  // namespace
}  // namespace doasido::filters
