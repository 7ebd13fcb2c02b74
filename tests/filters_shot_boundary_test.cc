// Shot-boundary scores against PySceneDetect's own golden cut lists for its
// test videos (../shared/data/shots/goldens/<video>.<Detector>.<variant>.json).
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "core/config.h"
#include "filters/frame_analyzer.h"
#include "filters/shot_boundary.h"
#include "test_util.h"

namespace doasido::filters {
namespace {

std::vector<std::int64_t> Golden(const std::string& name) {
  const auto path = testing::SharedData() / "shots" / "goldens" / name;
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  Json j = Json::parse(in);
  return j.at("cuts").get<std::vector<std::int64_t>>();
}

ShotSignals Signals(const std::string& video) {
  ShotSignalExtractor extractor;
  // PySceneDetect's pixels, as the analysis stage decodes by default.
  DecoderOptions exact;
  exact.exact_scaling = true;
  exact.skip_loop_filter = false;
  AnalyzeFrames(testing::SharedData() / "shots" / video, exact, {}, {&extractor});
  return extractor.signals();
}

TEST(Luma, EqualsOpenCVsYuvConversionForEveryColour) {
  // All 2^24 BGR colours, one image row per (B, G) pair.
  cv::Mat colours(256 * 256, 256, CV_8UC3);
  for (int b = 0; b < 256; ++b) {
    for (int g = 0; g < 256; ++g) {
      cv::Vec3b* row = colours.ptr<cv::Vec3b>(b * 256 + g);
      for (int r = 0; r < 256; ++r) row[r] = cv::Vec3b(b, g, r);
    }
  }
  cv::Mat yuv, opencv_y, ours;
  cv::cvtColor(colours, yuv, cv::COLOR_BGR2YUV);
  cv::extractChannel(yuv, opencv_y, 0);
  Luma(colours, &ours);
  EXPECT_EQ(cv::countNonZero(ours != opencv_y), 0);
  // A view that is not continuous (a column range) gives the same.
  cv::Mat part;
  Luma(colours.colRange(7, 200), &part);
  EXPECT_EQ(cv::countNonZero(part != opencv_y.colRange(7, 200)), 0);
}

class ShotGoldens : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() {}
};

TEST_P(ShotGoldens, EveryDetectorMatchesPySceneDetect) {
  const std::string video = GetParam();
  const ShotSignals s = Signals(video);
  ShotBoundaryConfig c;
  EXPECT_EQ(CutsOf("content", s, c), Golden(video + ".ContentDetector.default.json"));
  EXPECT_EQ(CutsOf("adaptive", s, c), Golden(video + ".AdaptiveDetector.default.json"));
  EXPECT_EQ(CutsOf("hash", s, c), Golden(video + ".HashDetector.default.json"));
  EXPECT_EQ(CutsOf("histogram", s, c), Golden(video + ".HistogramDetector.default.json"));
  EXPECT_EQ(CutsOf("fade", s, c), Golden(video + ".ThresholdDetector.default.json"));
  ShotBoundaryConfig t30;
  t30.content_threshold = 30;
  EXPECT_EQ(CutsOf("content", s, t30), Golden(video + ".ContentDetector.t30.json"));
  ShotBoundaryConfig t5;
  t5.adaptive_threshold = 5;
  EXPECT_EQ(CutsOf("adaptive", s, t5), Golden(video + ".AdaptiveDetector.t5.json"));

  // The cross-fade test stays quiet next to a known hard cut (it used to
  // add a boundary a few frames before each one: testvideo's 25 and 173).
  for (std::int64_t dissolve : CutsOf("dissolve", s, c)) {
    for (std::int64_t hard : Golden(video + ".AdaptiveDetector.default.json")) {
      EXPECT_GT(std::abs(dissolve - hard), s.long_window)
          << video << ": dissolve at " << dissolve << " beside the cut at " << hard;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Shots, ShotGoldens,
                         ::testing::Values("testvideo.mp4", "counter.mp4", "fades.mp4"));

}  // namespace
}  // namespace doasido::filters
