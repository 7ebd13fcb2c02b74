// Probing the real sample videos, checked against the data README and an
// independent ffprobe run.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "video/probe.h"
#include "tests/test_util.h"

namespace doasido::video {
namespace {

using doasido::testing::SharedData;

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

}  // namespace
}  // namespace doasido::video
