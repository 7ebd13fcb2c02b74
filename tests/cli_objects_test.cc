// `doasido objects` on files: 02_cups' first frames as a short clip and one
// of them as an image, the middle cup seeded where the hand-made labels put
// it: one JSON per input in the documented schema, the cup's centre on the
// labelled one, an overlay read back by OpenCV; a bad seed refused by
// name; and a real photo whose cup the 2D detector finds unaided.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/config.h"
#include "objects/objectron_models.h"
#include "test_util.h"
#include "video/mp4_writer.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;
using testing::RunDoasido;

TEST(CliObjects, WritesTheSeededCupsKeypointsForAClipAndAnImage) {
  std::string why;
  if (!objects::ObjectronModelFilesAvailable(&why)) GTEST_SKIP() << why;
  testing::TempDir tmp;
  cv::VideoCapture in((testing::SharedData() / "videos/02_cups.mp4").string());
  Mp4Writer out(tmp / "cups.mp4", 1280, 720, 30);
  cv::Mat frame;
  for (int i = 0; i < 8 && in.read(frame); ++i) {
    out.Write(frame);
    if (i == 0) cv::imwrite((tmp / "still.png").string(), frame);
  }
  out.Finish();
  // bench/object_labels/02_cups.json, frame 0: the middle cup's rims at
  // (656, 307) and (654, 523), its centre (655, 415).
  const testing::CommandResult r =
      RunDoasido({"objects", (tmp / "cups.mp4").string(), (tmp / "still.png").string(), "--out",
                  (tmp / "out").string(), "--categories", "cup", "--seed", "0:570,290,170,255",
                  "--overlay"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const auto& [stem, frames] : {std::pair{"cups", 8}, std::pair{"still", 1}}) {
    const Json j = Json::parse(testing::ReadFile(tmp / "out" / (std::string(stem) + ".json")));
    EXPECT_EQ(j.at("width"), 1280);
    EXPECT_EQ(j.at("height"), 720);
    ASSERT_EQ(j.at("frames").size(), static_cast<size_t>(frames)) << stem;
    const Json& first = j.at("frames").at(0);
    EXPECT_EQ(first.at("frame"), 0);
    ASSERT_EQ(first.at("objects").size(), 1u) << stem;
    const Json& cup = first.at("objects").at(0);
    EXPECT_EQ(cup.at("category"), "cup");
    EXPECT_GE(cup.at("score").get<double>(), 0.99);
    ASSERT_EQ(cup.at("keypoints_2d").size(), 9u);
    EXPECT_NEAR(cup.at("keypoints_2d").at(0).at(0).get<double>(), 655, 25) << stem;
    EXPECT_NEAR(cup.at("keypoints_2d").at(0).at(1).get<double>(), 415, 25) << stem;
    // Lifted: in front of the camera, a rotation, the cup prior's scale
    // (no hands in 3D here), and its centre on keypoint 0's ray.
    ASSERT_EQ(cup.at("center_camera").size(), 3u) << stem;
    const Eigen::Vector3d c(cup["center_camera"][0], cup["center_camera"][1], cup["center_camera"][2]);
    EXPECT_GT(c.z(), 0.1) << stem;
    Eigen::Matrix3d R;
    for (int row = 0; row < 3; ++row) {
      for (int k = 0; k < 3; ++k) R(row, k) = cup["rotation_camera"][row][k];
    }
    EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0, 1e-6) << stem;
    EXPECT_NEAR(R.determinant(), 1, 1e-6) << stem;
    EXPECT_TRUE(cup.at("scale_assumed").get<bool>()) << stem;
    ASSERT_EQ(cup.at("size_m").size(), 3u);
    // The prior's scale (an 11 oz mug) on the lifted proportions: measured
    // 0.142 m tall (a red plastic cup is about 0.12 m).
    EXPECT_GT(cup["size_m"][1].get<double>(), 0.06) << stem;
    EXPECT_LT(cup["size_m"][1].get<double>(), 0.2) << stem;
    const double f = 0.5 * 1280 / std::tan(0.5 * 65 * M_PI / 180);   // --fov's default
    const double u = f * c.x() / c.z() + 639.5 + 0.5, v = f * c.y() / c.z() + 359.5 + 0.5;
    EXPECT_NEAR(u, cup["keypoints_2d"][0][0].get<double>(), 30) << stem;
    EXPECT_NEAR(v, cup["keypoints_2d"][0][1].get<double>(), 30) << stem;
  }
  const cv::Mat overlay = cv::imread((tmp / "out/still.overlay.png").string());
  EXPECT_EQ(overlay.cols, 1280);
  EXPECT_GT(cv::VideoCapture((tmp / "out/cups.overlay.mp4").string()).get(cv::CAP_PROP_FRAME_COUNT), 0);

  const testing::CommandResult bad = RunDoasido(
      {"objects", (tmp / "still.png").string(), "--out", (tmp / "bad").string(), "--seed", "0:1,2,3"});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--seed"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(tmp / "bad/still.json"));
}

// A real photo the 2D detector finds unaided (no --seed): scikit-image's
// coffee cup (Debian python3-skimage, CC0; scripts/setup.sh --test installs
// it), labelled by hand in bench/object_labels/coffee.json. The box's top
// face (the mean of corners 3, 4, 7, 8) is the rim ellipse, so its centre
// must sit on the labelled rim centre and the box centre below it.
TEST(CliObjects, TheDetectorAloneFindsTheCupOfARealPhotoOnItsLabels) {
  std::string why;
  if (!objects::ObjectronModelFilesAvailable(&why)) GTEST_SKIP() << why;
  const Json labels = Json::parse(testing::ReadFile(testing::SourceDir() / "bench/object_labels/coffee.json"));
  const fs::path photo = labels.at("video").get<std::string>();
  ASSERT_TRUE(fs::exists(photo)) << photo << ": scripts/setup.sh --test installs python3-skimage";
  testing::TempDir tmp;
  const testing::CommandResult r =
      RunDoasido({"objects", photo.string(), "--out", (tmp / "out").string(), "--categories", "cup"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json j = Json::parse(testing::ReadFile(tmp / "out/coffee.json"));
  ASSERT_EQ(j.at("frames").size(), 1u);
  const Json& found = j.at("frames").at(0).at("objects");
  ASSERT_EQ(found.size(), 1u);
  const Json& cup = found.at(0);
  EXPECT_EQ(cup.at("category"), "cup");
  EXPECT_GE(cup.at("score").get<double>(), 0.99);
  const Json& k = cup.at("keypoints_2d");
  ASSERT_EQ(k.size(), 9u);
  Eigen::Vector2d top(0, 0);
  for (int i : {3, 4, 7, 8}) top += Eigen::Vector2d(k.at(i).at(0).get<double>(), k.at(i).at(1).get<double>()) / 4;
  const Json& label = labels.at("frames").at(0).at("cups").at(0);
  const Eigen::Vector2d upper(label.at("upper").at(0).get<double>(), label.at("upper").at(1).get<double>());
  const double rim_width = label.at("rim_right").at(0).get<double>() - label.at("rim_left").at(0).get<double>();
  EXPECT_LT((top - upper).norm(), 0.1 * rim_width) << "top face at " << top.transpose();
  EXPECT_GT(k.at(0).at(1).get<double>(), top.y()) << "the box centre lies below the rim: the cup stands";
}

// Bad input in a batch (ground rule 5): a truncated JPEG (decodes partly,
// with no cup) and a photo with no cup keep an entry per frame with no
// objects and an overlay; a file that is not an image fails alone, named;
// the coffee cup after them is still found. Options before the inputs take
// one value each (a list is comma-separated), so they leave the inputs be.
TEST(CliObjects, ABatchGoesOnPastPhotosWithoutACupAndAFileThatIsNotOne) {
  std::string why;
  if (!objects::ObjectronModelFilesAvailable(&why)) GTEST_SKIP() << why;
  const fs::path coffee = "/usr/lib/python3/dist-packages/skimage/data/coffee.png";
  const fs::path camera = "/usr/lib/python3/dist-packages/skimage/data/camera.png";
  ASSERT_TRUE(fs::exists(coffee) && fs::exists(camera)) << "scripts/setup.sh --test installs python3-skimage";
  testing::TempDir tmp;
  std::vector<uchar> jpeg;
  cv::imencode(".jpg", cv::imread(coffee.string()), jpeg);
  jpeg.resize(jpeg.size() / 8);  // the top of the picture: rim only, cut mid-stream
  testing::WriteFile(tmp / "cut.jpg", std::string(jpeg.begin(), jpeg.end()));
  testing::WriteFile(tmp / "notes.png", "not a picture\n");
  const testing::CommandResult r = RunDoasido({"objects", "--categories", "cup,chair", "--overlay", "--out",
                                               (tmp / "out").string(), (tmp / "cut.jpg").string(),
                                               camera.string(), (tmp / "notes.png").string(), coffee.string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("notes.png"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1 of 4 input(s) failed"), std::string::npos) << r.err;
  for (const char* stem : {"cut", "camera"}) {
    const Json j = Json::parse(testing::ReadFile(tmp / "out" / (std::string(stem) + ".json")));
    ASSERT_EQ(j.at("frames").size(), 1u) << stem;
    EXPECT_EQ(j.at("frames").at(0).at("objects").size(), 0u) << stem;
    EXPECT_FALSE(cv::imread((tmp / "out" / (std::string(stem) + ".overlay.png")).string()).empty()) << stem;
  }
  EXPECT_FALSE(fs::exists(tmp / "out/notes.json"));
  const Json cup = Json::parse(testing::ReadFile(tmp / "out/coffee.json"));
  ASSERT_EQ(cup.at("frames").at(0).at("objects").size(), 1u);
  EXPECT_EQ(cup.at("frames").at(0).at("objects").at(0).at("category"), "cup");
}

}  // namespace
}  // namespace doasido
