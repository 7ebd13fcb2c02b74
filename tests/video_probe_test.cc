// Probing the real sample videos, checked against the data README and an
// independent ffprobe run.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "core/error_codes.h"
#include "video/probe.h"
#include "video/video_decoder.h"
#include "tests/test_util.h"

namespace doasido::video {
namespace {

using doasido::testing::SharedData;
using doasido::testing::ShellOk;

struct FfprobeInfo {
  int width = 0, height = 0;
  long frames = 0;
  double fps = 0;
};

FfprobeInfo Ffprobe(const std::filesystem::path& file) {
  const std::string cmd =
      "ffprobe -v error -select_streams v:0 -count_frames -show_entries "
      "stream=width,height,nb_read_frames,r_frame_rate -of csv=p=0:nk=1 '" + file.string() + "'";
  FILE* pipe = popen(cmd.c_str(), "r");
  char buf[256] = {0};
  const size_t n = fread(buf, 1, sizeof buf - 1, pipe);
  pclose(pipe);
  FfprobeInfo info;
  int num = 0, den = 1;
  // ffprobe prints the entries in its own order: width,height,r_frame_rate,nb_read_frames
  std::sscanf(std::string(buf, n).c_str(), "%d,%d,%d/%d,%ld", &info.width, &info.height, &num,
              &den, &info.frames);
  info.fps = static_cast<double>(num) / den;
  return info;
}

struct Known {
  const char* file;
  int width, height;
  long frames;
  double fps;
};

TEST(Probe, RealVideosMatchTheirKnownFacts) {
  // From ../shared/data/README.md.
  const Known known[] = {{"videos/02_cups.mp4", 1280, 720, 300, 29.97},
                         {"videos/03_blocks.mp4", 1280, 720, 292, 29.97},
                         {"videos/bedroom.mp4", 960, 540, 200, 30.0},
                         {"videos/apple.mp4", 1296, 720, 50, 10.0},
                         {"shots/testvideo.mp4", 0, 0, 720, 0},
                         {"shots/fades.mp4", 0, 0, 250, 0},
                         {"shots/counter.mp4", 0, 0, 30, 0}};
  for (const auto& k : known) {
    const auto path = SharedData() / k.file;
    const VideoInfo info = ProbeVideo(path);
    const FfprobeInfo ff = Ffprobe(path);
    ASSERT_GT(ff.frames, 0) << "ffprobe failed on " << k.file;
    EXPECT_EQ(info.frame_count, k.frames) << k.file;
    EXPECT_EQ(info.frame_count, ff.frames) << k.file;
    EXPECT_EQ(info.width, ff.width) << k.file;
    EXPECT_EQ(info.height, ff.height) << k.file;
    EXPECT_NEAR(info.fps, ff.fps, 1e-3) << k.file;
    if (k.width > 0) {
      EXPECT_EQ(info.width, k.width) << k.file;
      EXPECT_EQ(info.height, k.height) << k.file;
      EXPECT_NEAR(info.fps, k.fps, 0.01) << k.file;
    }
    EXPECT_NEAR(info.duration_s, info.frame_count / info.fps, 1e-9);
    EXPECT_FALSE(info.codec.empty()) << k.file;
  }
}

TEST(Probe, TruncatedAndGarbageFilesFailWithNamedErrors) {
  doasido::testing::TempDir dir;
  const std::string bytes = doasido::testing::ReadFile(SharedData() / "videos" / "02_cups.mp4");
  const auto truncated = dir / "02_cups_truncated.mp4";
  doasido::testing::WriteFile(truncated, bytes.substr(0, bytes.size() / 2));
  try {
    ProbeVideo(truncated);
    FAIL() << "a half file probed fine";
  } catch (const Error& e) {
    EXPECT_TRUE(e.code() == "video_truncated" || e.code() == "video_unreadable") << e.what();
    EXPECT_NE(std::string(e.what()).find("02_cups_truncated.mp4"), std::string::npos);
  }
  const auto garbage = dir / "garbage.mp4";
  doasido::testing::WriteFile(garbage, std::string(4096, 'x'));
  try {
    ProbeVideo(garbage);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "video_unreadable") << e.what();
  }
  try {
    ProbeVideo(dir / "absent.mp4");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "video_missing");
  }
}

TEST(Probe, EveryRealVideoMatchesFfprobeCountFrames) {
  int checked = 0;
  for (const char* folder : {"videos", "shots"}) {
    for (const auto& entry : std::filesystem::directory_iterator(SharedData() / folder)) {
      const auto ext = entry.path().extension();
      if (ext != ".mp4" && ext != ".avi") continue;
      const VideoInfo info = ProbeVideo(entry.path());
      const FfprobeInfo ff = Ffprobe(entry.path());
      EXPECT_EQ(info.frame_count, ff.frames) << entry.path();
      EXPECT_EQ(info.width, ff.width) << entry.path();
      EXPECT_EQ(info.height, ff.height) << entry.path();
      EXPECT_NEAR(info.fps, ff.fps, 1e-3) << entry.path();
      // Rotation as OpenCV (and players) apply it.
      cv::VideoCapture cap(entry.path().string(), cv::CAP_FFMPEG);
      EXPECT_EQ(info.rotation_deg, static_cast<int>(cap.get(cv::CAP_PROP_ORIENTATION_META)))
          << entry.path();
      ++checked;
    }
  }
  EXPECT_GE(checked, 15);
}

TEST(Probe, ConstantRateIsNotVariableAndVariableIs) {
  doasido::testing::TempDir dir;
  // libx264 with B-frames: packets arrive out of presentation order.
  ShellOk("ffmpeg -v error -f lavfi -i testsrc=size=64x48:rate=30 -frames:v 90 -c:v libx264 "
        "-bf 3 " + (dir / "cfr.mp4").string());
  ShellOk("ffmpeg -v error -f lavfi -i testsrc=size=64x48:rate=30 -frames:v 90 "
        "-vf \"setpts='if(lt(N,45),N,45+2*(N-45))/30/TB'\" -fps_mode vfr -c:v libx264 " +
        (dir / "vfr.mp4").string());
  EXPECT_FALSE(ProbeVideo(dir / "cfr.mp4").variable_frame_rate);
  EXPECT_EQ(ProbeVideo(dir / "cfr.mp4").frame_count, 90);
  EXPECT_TRUE(ProbeVideo(dir / "vfr.mp4").variable_frame_rate);
  for (const char* f : {"02_cups.mp4", "03_blocks.mp4", "bedroom.mp4"}) {
    EXPECT_FALSE(ProbeVideo(SharedData() / "videos" / f).variable_frame_rate) << f;
  }
}

TEST(Probe, RotationFromTheDisplayMatrix) {
  doasido::testing::TempDir dir;
  ShellOk("ffmpeg -v error -f lavfi -i testsrc=size=64x48:rate=30 -frames:v 10 " +
        (dir / "plain.mp4").string());
  ShellOk("ffmpeg -v error -i " + (dir / "plain.mp4").string() +
        " -c copy -metadata:s:v:0 rotate=90 " + (dir / "rotated.mp4").string());
  const VideoInfo info = ProbeVideo(dir / "rotated.mp4");
  cv::VideoCapture cap((dir / "rotated.mp4").string(), cv::CAP_FFMPEG);
  EXPECT_EQ(info.rotation_deg, static_cast<int>(cap.get(cv::CAP_PROP_ORIENTATION_META)));
  EXPECT_EQ(info.rotation_deg, 90);
  EXPECT_EQ(info.width, 48);  // the size as displayed, as the decoder delivers it
  EXPECT_EQ(info.height, 64);
  EXPECT_EQ(ProbeVideo(dir / "plain.mp4").rotation_deg, 0);

  // Decoding turns the frames as players do: display size, and the same
  // pixels as ffmpeg's own (auto-rotating) decode of the first frame.
  ShellOk("ffmpeg -v error -i " + (dir / "rotated.mp4").string() + " -frames:v 1 " +
        (dir / "first.png").string());
  const cv::Mat expected = cv::imread((dir / "first.png").string());
  ASSERT_EQ(expected.cols, 48);
  ASSERT_EQ(expected.rows, 64);
  DecoderOptions options;
  options.analysis_size = 0;
  options.exact_scaling = true;
  options.skip_loop_filter = false;
  VideoDecoder decoder(dir / "rotated.mp4", options);
  EXPECT_EQ(decoder.geometry().full_width, 48);
  EXPECT_EQ(decoder.geometry().full_height, 64);
  AnalysisFrame frame;
  ASSERT_TRUE(decoder.Next(&frame));
  ASSERT_EQ(frame.bgr.size(), expected.size());
  cv::Mat diff;
  cv::absdiff(frame.bgr, expected, diff);
  EXPECT_LT(cv::mean(diff)[0], 3.0) << "turned the wrong way?";
  // And at analysis size.
  DecoderOptions small;
  small.analysis_size = 32;
  VideoDecoder scaled(dir / "rotated.mp4", small);
  ASSERT_TRUE(scaled.Next(&frame));
  EXPECT_EQ(frame.bgr.cols, 24);
  EXPECT_EQ(frame.bgr.rows, 32);
}

// A faststart MP4 (index first) cut at `offset` bytes.
std::filesystem::path Cut(const doasido::testing::TempDir& dir, const std::string& name,
                          const std::string& bytes, size_t offset) {
  doasido::testing::WriteFile(dir / name, bytes.substr(0, offset));
  return dir / name;
}

TEST(Probe, ShortTailPassesProbeAndDecodeTruncationFailsBothOnce) {
  doasido::testing::TempDir dir;
  ShellOk("ffmpeg -v error -f lavfi -i testsrc=size=64x48:rate=30 -frames:v 60 -c:v libx264 -bf 0 "
        "-movflags +faststart " + (dir / "whole.mp4").string());
  const std::string bytes = doasido::testing::ReadFile(dir / "whole.mp4");
  // The last packet's offset: the file ends just before it, so the index
  // declares one frame more than the file holds.
  const std::string last = ShellOk("ffprobe -v error -select_streams v:0 -show_entries packet=pos "
                                 "-of csv=p=0 " + (dir / "whole.mp4").string() + " | tail -1");
  const auto tail = Cut(dir, "tail.mp4", bytes, std::stoul(last));
  const VideoInfo info = ProbeVideo(tail);
  EXPECT_EQ(info.frame_count, 59);
  DecoderOptions options;
  options.last_frame = 59;  // the span the list gives: the declared last frame
  VideoDecoder decoder(tail, options);
  AnalysisFrame frame;
  int frames = 0;
  while (decoder.Next(&frame)) ++frames;
  EXPECT_EQ(frames, 59);

  const auto half = Cut(dir, "half.mp4", bytes, bytes.size() / 2);
  try {
    ProbeVideo(half);
    FAIL() << "a half file probed fine";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "video_truncated") << e.what();
    EXPECT_TRUE(IsPermanentError(e.code())) << "a retry cannot fix it";
    EXPECT_NE(std::string(e.what()).find("half.mp4"), std::string::npos);
  }
  try {
    VideoDecoder d(half, DecoderOptions{});
    while (d.Next(&frame)) {
    }
    FAIL() << "a half file decoded fine";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "video_truncated") << e.what();
    EXPECT_TRUE(IsPermanentError(e.code()));
  }
}

}  // namespace
}  // namespace doasido::video
