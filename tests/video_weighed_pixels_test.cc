// The exact decode's shortcut: converting only the pixels cv::resize
// weighs gives the bytes of converting every pixel and resizing, on every
// real sample video; and the taps are OpenCV's.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "test_util.h"
#include "video/video_decoder.h"
#include "video/weighed_pixels.h"

namespace doasido {
namespace {

TEST(WeighedTaps, AWholeFactorWeighsOneColumnInFive) {
  // 1280 -> 256: output d's centre falls on source 5 d + 2 exactly.
  const std::vector<int> taps = WeighedTaps(1280, 256);
  ASSERT_EQ(taps.size(), 256u);
  for (int d = 0; d < 256; ++d) EXPECT_EQ(taps[d], 5 * d + 2);
  // The same size: every column, once.
  EXPECT_EQ(WeighedTaps(7, 7), (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));
}

TEST(WeighedTaps, AFractionalFactorWeighsBothNeighbours) {
  // 960 -> 256 (x3.75): output 0 at source 1.375, i.e. columns 1 and 2.
  const std::vector<int> taps = WeighedTaps(960, 256);
  EXPECT_EQ(taps[0], 1);
  EXPECT_EQ(taps[1], 2);
  EXPECT_EQ(taps.size(), 512u);
  for (int t : taps) {
    EXPECT_GE(t, 0);
    EXPECT_LT(t, 960);
  }
}

// Every frame of `video` through the exact path, and the reference made
// here the slow way: every pixel converted (analysis size 0), then
// cv::resize to the analysis size.
void ExpectSameAsTheFullConversion(const std::filesystem::path& video, bool weighed_expected) {
  SCOPED_TRACE(video.filename().string());
  DecoderOptions exact{.skip_loop_filter = false, .exact_scaling = true};
  DecoderOptions whole{.analysis_size = 0, .skip_loop_filter = false};
  VideoDecoder decoder(video, exact), reference(video, whole);
  const cv::Size size(decoder.geometry().width, decoder.geometry().height);
  AnalysisFrame frame, full;
  int frames = 0, differing = 0;
  while (decoder.Next(&frame)) {
    ASSERT_TRUE(reference.Next(&full));
    cv::Mat expected;
    cv::resize(full.bgr, expected, size, 0, 0, cv::INTER_LINEAR);
    differing += cv::norm(frame.bgr, expected, cv::NORM_INF) != 0;
    ++frames;
  }
  EXPECT_FALSE(reference.Next(&full));
  EXPECT_GT(frames, 0);
  EXPECT_EQ(differing, 0) << "of " << frames << " frames";
  EXPECT_EQ(decoder.converts_weighed_pixels(), weighed_expected);
}

TEST(WeighedPixels, EveryRealSampleVideoDecodesToTheFullConversionsBytes) {
  const std::filesystem::path data = testing::SharedData();
  // 1280x720 and 1920x1080 shrink to 256 wide: the shortcut runs.
  for (const char* v : {"videos/02_cups.mp4", "videos/03_blocks.mp4", "videos/laptop_trackpad.mp4",
                        "shots/testvideo.mp4", "retarget/human_hand_video.mp4"}) {
    ExpectSameAsTheFullConversion(data / v, true);
  }
  // Smaller shrinks (bedroom x3.75, apple x5.06 with both taps weighed),
  // frames already small (eyeliner), and 4:4:4 (asl_hand) convert every
  // pixel.
  for (const char* v : {"videos/bedroom.mp4", "videos/bass_guitar.mp4", "videos/eyeliner.avi",
                        "videos/apple.mp4",
                        "videos/asl_hand.mp4", "videos/making_cake.mp4", "videos/yoga.mp4"}) {
    ExpectSameAsTheFullConversion(data / v, false);
  }
}

}  // namespace
}  // namespace doasido
