// The single-pass frame decoder: analysis size, spans, timestamps and clear
// errors for missing and truncated files.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "video/video_decoder.h"
#include "test_util.h"

namespace doasido {
namespace {

std::filesystem::path Cups() { return testing::SharedData() / "videos" / "02_cups.mp4"; }

// Copies the first half of the bytes of `from` to `to`.
void CopyFirstHalf(const std::filesystem::path& from, const std::filesystem::path& to) {
  std::ifstream in(from, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream out(to, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size() / 2));
}

TEST(AnalysisSize, FollowsPySceneDetectDownscale) {
  // factor = longer side / 256, sides rounded half to even.
  EXPECT_DOUBLE_EQ(AnalysisDownscale(1280, 720, 256), 5.0);
  EXPECT_EQ(AnalysisSize(1280, 720, 256), cv::Size(256, 144));
  EXPECT_EQ(AnalysisSize(1920, 1080, 256), cv::Size(256, 144));
  EXPECT_EQ(AnalysisSize(480, 320, 256), cv::Size(256, 171));   // 170.67
  EXPECT_EQ(AnalysisSize(1296, 720, 256), cv::Size(256, 142));  // 142.2
  EXPECT_EQ(AnalysisSize(720, 1280, 256), cv::Size(144, 256));  // portrait: longer side
  EXPECT_EQ(AnalysisSize(200, 100, 256), cv::Size(200, 100));   // never upscaled
  EXPECT_EQ(AnalysisSize(1280, 720, 0), cv::Size(1280, 720));   // 0 keeps full size
  // 100 / (1000/256) = 25.6 -> 26; 1000 / 3.90625 = 256.
  EXPECT_EQ(AnalysisSize(1000, 100, 256), cv::Size(256, 26));
}

TEST(VideoDecoder, DecodesEveryFrameAtAnalysisSize) {
  VideoDecoder decoder(Cups(), {});
  EXPECT_EQ(decoder.geometry().full_width, 1280);
  EXPECT_EQ(decoder.geometry().full_height, 720);
  EXPECT_EQ(decoder.geometry().width, 256);
  EXPECT_EQ(decoder.geometry().height, 144);
  EXPECT_NEAR(decoder.geometry().fps, 30000.0 / 1001.0, 1e-6);
  AnalysisFrame frame;
  std::int64_t expected = 0;
  double last_t = -1;
  while (decoder.Next(&frame)) {
    EXPECT_EQ(frame.index, expected++);
    EXPECT_EQ(frame.bgr.size(), cv::Size(256, 144));
    EXPECT_EQ(frame.bgr.type(), CV_8UC3);
    EXPECT_GT(frame.timestamp_s, last_t);
    last_t = frame.timestamp_s;
  }
  EXPECT_EQ(expected, 300);  // the data README: 300 frames
  EXPECT_NEAR(last_t, 299 * 1001.0 / 30000.0, 1e-3);
}

// libswscale stores up to a few dozen bytes past its last output row (24
// behind yoga.mp4's 568-pixel rows: heap corruption that aborted one run in
// two). Every frame the scaler writes (analysis size; full size on the exact
// path), for every real video, is a
// continuous image with room behind it.
TEST(VideoDecoder, FramesLeaveRoomForTheScalersOverrun) {
  for (const auto& entry : std::filesystem::directory_iterator(testing::SharedData() / "videos")) {
    const auto ext = entry.path().extension();
    if (ext != ".mp4" && ext != ".avi") continue;
    for (const bool exact : {false, true}) {
      DecoderOptions options;
      options.exact_scaling = exact;
      if (exact) options.analysis_size = 0;  // the frame is the scaler's full-size output
      options.last_frame = 1;
      VideoDecoder decoder(entry.path(), options);
      AnalysisFrame frame;
      int frames = 0;
      while (decoder.Next(&frame)) {
        ++frames;
        EXPECT_TRUE(frame.bgr.isContinuous()) << entry.path();
        EXPECT_GE(frame.bgr.datalimit - (frame.bgr.data + frame.bgr.total() * 3), 64) << entry.path() << " exact " << exact;
      }
      EXPECT_EQ(frames, 2) << entry.path();
    }
  }
}

TEST(VideoDecoder, DeliversOnlyTheSpan) {
  DecoderOptions options;
  options.first_frame = 100;
  options.last_frame = 119;
  VideoDecoder decoder(Cups(), options);
  AnalysisFrame frame;
  std::vector<std::int64_t> got;
  while (decoder.Next(&frame)) got.push_back(frame.index);
  ASSERT_EQ(got.size(), 20u);
  EXPECT_EQ(got.front(), 100);
  EXPECT_EQ(got.back(), 119);
  EXPECT_NEAR(frame.timestamp_s, 119 * 1001.0 / 30000.0, 1e-3);
}

// Seeking to a late span must deliver exactly the frames a decode from the
// start delivers (same indices, same pixels, same timestamps).
TEST(VideoDecoder, SeekingToASpanEqualsDecodingFromTheStart) {
  for (const auto& [video, first] : {std::pair{"shots/testvideo.mp4", 400},
                                     std::pair{"videos/02_cups.mp4", 233},
                                     std::pair{"shots/fades.mp4", 101}}) {
    DecoderOptions seek;
    seek.first_frame = first;
    seek.last_frame = first + 24;
    seek.seek_after_frames = 1;
    DecoderOptions count = seek;
    count.seek_after_frames = 0;  // never seek
    VideoDecoder a(testing::SharedData() / video, seek), b(testing::SharedData() / video, count);
    AnalysisFrame fa, fb;
    int n = 0;
    while (b.Next(&fb)) {
      ASSERT_TRUE(a.Next(&fa)) << video << " frame " << fb.index;
      EXPECT_EQ(fa.index, fb.index) << video;
      EXPECT_NEAR(fa.timestamp_s, fb.timestamp_s, 1e-6) << video;
      EXPECT_EQ(cv::norm(fa.bgr, fb.bgr, cv::NORM_INF), 0.0) << video << " frame " << fb.index;
      ++n;
    }
    EXPECT_FALSE(a.Next(&fa));
    EXPECT_EQ(n, 25) << video;
  }
}

// The worst per-frame mean |difference| between a decode with `options`
// and PySceneDetect's path (deblocked, full-size BGR, cv::resize).
double WorstMeanDifference(const DecoderOptions& options) {
  DecoderOptions exact;
  exact.exact_scaling = true;
  exact.skip_loop_filter = false;
  VideoDecoder a(Cups(), options), b(Cups(), exact);
  AnalysisFrame fa, fb;
  double worst = 0;
  while (a.Next(&fa) && b.Next(&fb)) {
    cv::Mat diff;
    cv::absdiff(fa.bgr, fb.bgr, diff);
    worst = std::max(worst, cv::mean(diff)[0]);
  }
  return worst;
}

// Skipping the deblocking filter drifts only until the next key frame, a
// couple of grey levels; libswscale's bilinear (which low-passes) differs
// from cv::resize's (which samples 2x2 pixels at a factor of 5) by a few
// more on textured frames. Measured: 2.5 and 5.5 on 02_cups.
TEST(VideoDecoder, FastPathIsCloseToTheExactPath) {
  DecoderOptions deblock_only;
  deblock_only.exact_scaling = true;
  const double deblock = WorstMeanDifference(deblock_only);
  EXPECT_GT(deblock, 0.0);  // the paths do differ
  EXPECT_LT(deblock, 3.0);
  EXPECT_LT(WorstMeanDifference({}), 6.5);
}

TEST(VideoDecoder, SpanInSecondsUsesTheFrameRate) {
  DecoderOptions options;
  options.first_s = 2.0;  // 2 s * 29.97 = 59.94 -> frame 60
  options.last_s = 3.0;   // 89.91 -> frame 90
  VideoDecoder decoder(Cups(), options);
  EXPECT_EQ(decoder.first_frame(), 60);
  AnalysisFrame frame;
  std::int64_t n = 0, last = -1;
  while (decoder.Next(&frame)) {
    ++n;
    last = frame.index;
  }
  EXPECT_EQ(n, 31);
  EXPECT_EQ(last, 90);
}

TEST(VideoDecoder, MissingFileIsAClearError) {
  try {
    VideoDecoder decoder(testing::SharedData() / "videos" / "no_such.mp4", {.clip = "c7"});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "video_open_failed");
    EXPECT_EQ(e.site().clip, "c7");
    EXPECT_NE(std::string(e.what()).find("no_such.mp4"), std::string::npos);
  }
}

TEST(VideoDecoder, TruncatedFileNamesFileAndFrame) {
  testing::TempDir dir;
  const auto truncated = dir / "cups_half.mp4";
  CopyFirstHalf(Cups(), truncated);
  DecoderOptions options;
  options.clip = "cups-half";
  std::int64_t delivered = 0;
  try {
    VideoDecoder decoder(truncated, options);
    AnalysisFrame frame;
    while (decoder.Next(&frame)) ++delivered;
    FAIL() << "decoded " << delivered << " frames without an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "video_truncated") << e.what();
    EXPECT_EQ(e.site().file, truncated.string());
    EXPECT_EQ(e.site().clip, "cups-half");
    // The first frame it could not decode, out of the 300 the file declares.
    EXPECT_EQ(e.site().field, "frame " + std::to_string(delivered));
    EXPECT_GT(delivered, 50);
    EXPECT_LT(delivered, 300);
    EXPECT_NE(std::string(e.what()).find("of 300 declared"), std::string::npos) << e.what();
  }
}

TEST(VideoDecoder, FileCutBeforeItsIndexCannotBeOpened) {
  // testvideo.mp4 keeps its index (moov) at the end: half a file has none.
  testing::TempDir dir;
  const auto truncated = dir / "testvideo_half.mp4";
  CopyFirstHalf(testing::SharedData() / "shots" / "testvideo.mp4", truncated);
  try {
    VideoDecoder decoder(truncated, {});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "video_open_failed");
    EXPECT_EQ(e.site().file, truncated.string());
  }
}

}  // namespace
}  // namespace doasido

namespace doasido {
namespace {

// The first frame of `video` through the exact path, and the frame after it.
std::vector<cv::Mat> FirstFrames(const std::filesystem::path& video) {
  VideoDecoder decoder(video, {.skip_loop_filter = false, .exact_scaling = true});
  AnalysisFrame frame;
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 2 && decoder.Next(&frame); ++i) frames.push_back(frame.bgr.clone());
  return frames;
}

TEST(VideoDecoder, AFrameDoesNotDependOnWhatWasDecodedBefore) {
  // 470 pixels wide: libswscale's converter at that size leaves the last 6
  // columns unwritten; they used to hold whatever the buffer held.
  const auto bass = testing::SharedData() / "videos" / "bass_guitar.mp4";
  const std::vector<cv::Mat> first = FirstFrames(bass);
  FirstFrames(Cups());
  FirstFrames(testing::SharedData() / "videos" / "yoga.mp4");  // 568 wide
  const std::vector<cv::Mat> again = FirstFrames(bass);
  ASSERT_EQ(first.size(), 2u);
  ASSERT_EQ(again.size(), 2u);
  for (int i = 0; i < 2; ++i) EXPECT_EQ(cv::norm(first[i], again[i], cv::NORM_INF), 0) << i;
  // The full-size conversion's last columns are real pixels of the frame:
  // they continue the columns before them.
  VideoDecoder whole(bass, {.analysis_size = 0, .skip_loop_filter = false});
  AnalysisFrame frame;
  ASSERT_TRUE(whole.Next(&frame));
  ASSERT_EQ(frame.bgr.cols, 470);
  cv::Mat last, before;
  frame.bgr.colRange(464, 470).convertTo(last, CV_32F);
  frame.bgr.colRange(458, 464).convertTo(before, CV_32F);
  EXPECT_LT(std::abs(cv::mean(last)[0] - cv::mean(before)[0]), 20.0);
}

}  // namespace
}  // namespace doasido
