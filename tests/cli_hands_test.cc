// `doasido hands` on files: one JSON per input in the documented schema, an
// overlay read back by OpenCV, and bad inputs named while the others run.
#include <gtest/gtest.h>

#include <map>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "core/config.h"
#include "db/database.h"
#include "filters/hand_landmarker.h"
#include "test_util.h"
#include "video/mp4_writer.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;
using testing::RunDoasido;

class CliHandsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!filters::HandLandmarkerAvailable(&why)) GTEST_SKIP() << "hand models unavailable: " << why;
    // A short clip (the first 6 frames of a real one) and one of its frames as an image.
    cv::VideoCapture in((testing::SharedData() / "videos/eyeliner.avi").string());
    Mp4Writer out(tmp_ / "pencil.mp4", 320, 240, 25);
    cv::Mat frame;
    for (int i = 0; i < 6 && in.read(frame); ++i) {
      out.Write(frame);
      if (i == 2) cv::imwrite((tmp_ / "still.png").string(), frame);
    }
    out.Finish();
  }
  void ExpectSchema(const Json& j, size_t frames, int width, int height) {
    EXPECT_EQ(j.at("width"), width);
    EXPECT_EQ(j.at("height"), height);
    ASSERT_EQ(j.at("frames").size(), frames);
    int hands = 0;
    for (size_t i = 0; i < frames; ++i) {
      const Json& f = j.at("frames")[i];
      EXPECT_EQ(f.at("frame"), i);
      for (const Json& h : f.at("hands")) {
        ++hands;
        EXPECT_TRUE(h.at("side") == "right" || h.at("side") == "left");
        EXPECT_GT(h.at("score").get<double>(), 0.0);
        ASSERT_EQ(h.at("keypoints_2d").size(), 21u);
        ASSERT_EQ(h.at("confidence").size(), 21u);
        ASSERT_EQ(h.at("joints_camera").size(), 21u);
        for (const Json& p : h.at("keypoints_2d")) ASSERT_EQ(p.size(), 2u);
        for (const Json& p : h.at("joints_camera")) {
          ASSERT_EQ(p.size(), 3u);
          EXPECT_GT(p[2].get<double>(), 0.0);
        }
        // Keypoints lie on (or near) the picture.
        EXPECT_GT(h.at("keypoints_2d")[0][0].get<double>(), -0.2 * width);
        EXPECT_LT(h.at("keypoints_2d")[0][0].get<double>(), 1.2 * width);
      }
    }
    EXPECT_GE(hands, static_cast<int>(frames));  // the pencil hand on every frame
  }
  testing::TempDir tmp_;
};

TEST_F(CliHandsTest, VideoAndImageGiveJsonAndOverlays) {
  const auto r = RunDoasido({"hands", (tmp_ / "pencil.mp4").string(), (tmp_ / "still.png").string(),
                             "--out", (tmp_ / "out").string(), "--overlay", "--fov", "60"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json video = Json::parse(testing::ReadFile(tmp_ / "out/pencil.json"));
  ExpectSchema(video, 6, 320, 240);
  EXPECT_EQ(video.at("intrinsics_assumed"), false);
  EXPECT_NEAR(video.at("K")[0][0].get<double>(), 160 / std::tan(30 * M_PI / 180), 1e-6);
  const Json image = Json::parse(testing::ReadFile(tmp_ / "out/still.json"));
  ExpectSchema(image, 1, 320, 240);
  cv::VideoCapture overlay((tmp_ / "out/pencil.overlay.mp4").string());
  ASSERT_TRUE(overlay.isOpened());
  EXPECT_EQ(overlay.get(cv::CAP_PROP_FRAME_COUNT), 6);
  cv::Mat first;
  ASSERT_TRUE(overlay.read(first));
  EXPECT_EQ(first.cols, 320);
  const cv::Mat png = cv::imread((tmp_ / "out/still.overlay.png").string());
  ASSERT_FALSE(png.empty());
  // The overlay differs from the input where the skeleton is drawn.
  const cv::Mat still = cv::imread((tmp_ / "still.png").string());
  EXPECT_GT(cv::norm(png, still, cv::NORM_L1) / png.total(), 0.5);
}

TEST_F(CliHandsTest, BadInputsAreNamedAndTheOthersStillRun) {
  testing::WriteFile(tmp_ / "junk.mp4", std::string(4000, 'x'));
  const auto r = RunDoasido({"hands", (tmp_ / "missing.mp4").string(), (tmp_ / "junk.mp4").string(),
                             (tmp_ / "still.png").string(), "--out", (tmp_ / "out").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("missing.mp4"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("junk.mp4"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("2 of 3"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(tmp_ / "out/still.json"));
  EXPECT_FALSE(fs::exists(tmp_ / "out/junk.json"));
  const Json image = Json::parse(testing::ReadFile(tmp_ / "out/still.json"));
  EXPECT_EQ(image.at("intrinsics_assumed"), true);
}

TEST_F(CliHandsTest, BadOptionsAreRefusedBeforeAnyWork) {
  auto r = RunDoasido({"hands", (tmp_ / "still.png").string(), "--out", (tmp_ / "o").string(), "--fov", "200"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--fov"), std::string::npos) << r.err;
  r = RunDoasido({"hands", (tmp_ / "still.png").string(), "--out", (tmp_ / "o").string(), "--fx", "500",
                  "--fov", "60"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_FALSE(fs::exists(tmp_ / "o/still.json"));
}

TEST_F(CliHandsTest, TheStageRunsInTheQueueAndNamesABadClip) {
  // A list with a good clip (its camera given as a field of view) and one
  // whose fov column is not a number.
  const std::string video = (tmp_ / "pencil.mp4").string();
  testing::WriteFile(tmp_ / "list.csv", "video,id,start_frame,end_frame,fov\n" + video + ",pencil,0,5,60\n" +
                                            video + ",badfov,0,4,wide\n");
  testing::WriteFile(tmp_ / "hands.toml", "[hands.tracker]\nmax_gap_frames = 3\n");
  const std::string db = (tmp_ / "q/d.db").string();
  ASSERT_EQ(RunDoasido({"init", "--db", db, "--pipeline", "probe,hands"}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", db, "--config", (tmp_ / "hands.toml").string(), "--max-attempts",
                               "1", (tmp_ / "list.csv").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Database check(db);
  std::map<std::string, StageRunRow> runs;
  for (const StageRunRow& r : check.ListRuns({})) {
    if (r.stage == "hands") runs[r.external_id] = r;
  }
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(ToString(runs.at("pencil").state), std::string("done")) << runs.at("pencil").error;
  EXPECT_EQ(runs.at("pencil").verdict, "pass");
  const fs::path dir = check.ArtifactDir(runs.at("pencil").clip_id, "hands");
  const Json meta = Json::parse(testing::ReadFile(dir / "meta.json"));
  EXPECT_EQ(meta.at("frames"), 6);
  EXPECT_EQ(meta.at("intrinsics_assumed"), false);
  EXPECT_TRUE(fs::exists(dir / "hands.npz"));
  EXPECT_EQ(ToString(runs.at("badfov").state), std::string("failed"));
  EXPECT_NE(runs.at("badfov").error.find("bad_intrinsics"), std::string::npos) << runs.at("badfov").error;
  EXPECT_NE(runs.at("badfov").error.find("clip badfov"), std::string::npos) << runs.at("badfov").error;
  EXPECT_NE(runs.at("badfov").error.find("field fov"), std::string::npos) << runs.at("badfov").error;

  // A [hands] value out of range is refused before any clip runs.
  testing::WriteFile(tmp_ / "bad.toml", "[hands]\ndefault_fov_deg = 500\n");
  const auto refused = RunDoasido({"run", "--db", db, "--config", (tmp_ / "bad.toml").string()});
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("hands.default_fov_deg"), std::string::npos) << refused.err;
}

}  // namespace
}  // namespace doasido
