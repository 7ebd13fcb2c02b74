// `doasido hand import` and `doasido hand check` as a user runs them, and a
// URDF given where a hand is expected.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/config.h"
#include "robot/embodiment.h"
#include "tests/test_util.h"
#include "tests/two_finger_hand.h"

namespace doasido::testing {
namespace {

// Fraction of pixels that are not the white background.
double Covered(const cv::Mat& image) {
  cv::Mat mask = image != cv::Vec3b(255, 255, 255);
  cv::Mat channels[3];
  cv::split(mask, channels);
  cv::Mat any = channels[0] | channels[1] | channels[2];
  return cv::countNonZero(any) / static_cast<double>(image.total());
}

TEST(CliHand, ImportThenCheckDrawsTheHandRestingAndFlexed) {
  TempDir dir;
  const auto urdf = WriteTwoFingerHand(dir / "src");
  const CommandResult imported =
      RunDoasido({"hand", "import", "--urdf", urdf.string(), "--out", (dir / "hand").string()});
  ASSERT_EQ(imported.exit_code, 0) << imported.err;
  EXPECT_NE(imported.out.find("converted"), std::string::npos) << imported.out;  // the PLY palm
  const std::string desc = (dir / "hand/two_finger.json").string();
  EXPECT_NE(imported.out.find("next: doasido hand check " + desc), std::string::npos) << imported.out;

  const CommandResult check = RunDoasido({"hand", "check", desc, "--out", (dir / "pictures").string()});
  ASSERT_EQ(check.exit_code, 0) << check.out << check.err;
  for (const char* line : {"thumb   thumb_metacarpal > thumb_proximal > thumb_distal > thumb_tip",
                           "index   index_knuckle > index_proximal > index_middle > index_distal > index_tip",
                           "index_dip", "problems: none"}) {
    EXPECT_NE(check.out.find(line), std::string::npos) << line << "\n" << check.out;
  }
  // Read back by OpenCV's PNG decoder: the hand covers part of the picture,
  // and flexing the fingers changes it.
  const cv::Mat rest = cv::imread((dir / "pictures/two_finger_rest.png").string());
  const cv::Mat flexed = cv::imread((dir / "pictures/two_finger_flexed.png").string());
  ASSERT_FALSE(rest.empty());
  ASSERT_FALSE(flexed.empty());
  EXPECT_GT(Covered(rest), 0.05);
  EXPECT_LT(Covered(rest), 0.9);
  cv::Mat diff;
  cv::absdiff(rest, flexed, diff);
  EXPECT_GT(Covered(cv::Scalar::all(255) - diff), 0.01) << "flexed picture differs from the rest picture";
}

TEST(CliHand, CheckNamesProblemsAndExitsOne) {
  TempDir dir;
  RunDoasido({"hand", "import", "--urdf", WriteTwoFingerHand(dir / "src").string(), "--out", (dir / "hand").string()});
  std::string json = ReadFile(dir / "hand/two_finger.json");
  const size_t at = json.find("\"index_tip\"");
  ASSERT_NE(at, std::string::npos);
  json.replace(at, 11, "\"index_nail\"");
  WriteFile(dir / "hand/two_finger.json", json);
  const CommandResult check =
      RunDoasido({"hand", "check", (dir / "hand/two_finger.json").string(), "--no-pictures"});
  EXPECT_EQ(check.exit_code, 1);
  EXPECT_NE(check.out.find("missing_body: points["), std::string::npos) << check.out;
  EXPECT_NE(check.out.find("index_nail"), std::string::npos) << check.out;
  EXPECT_NE(check.err.find("hand_problems"), std::string::npos) << check.err;
}

// A left Shadow hand from the right one, mirrored back: the description
// returns to the right side with the right hand's points.
TEST(CliHand, MirrorMakesALeftHandAndMirroringBackTheRightOne) {
  TempDir dir;
  const CommandResult left = RunDoasido({"hand", "mirror", "shadow", "--out", (dir / "left").string()});
  ASSERT_EQ(left.exit_code, 0) << left.out << left.err;
  EXPECT_NE(left.out.find("shadow_right (right) mirrored through y = 0: shadow_left (left)"), std::string::npos)
      << left.out;
  EXPECT_NE(left.out.find("problems: none"), std::string::npos) << left.out;
  const CommandResult check =
      RunDoasido({"hand", "check", (dir / "left/shadow_left.json").string(), "--no-pictures"});
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
  EXPECT_NE(check.out.find("hand shadow_left (left)"), std::string::npos) << check.out;

  const CommandResult back = RunDoasido(
      {"hand", "mirror", (dir / "left/shadow_left.json").string(), "--out", (dir / "back").string()});
  ASSERT_EQ(back.exit_code, 0) << back.out << back.err;
  // Compared as descriptions (the file spells defaults out).
  const auto original =
      Json::parse(ReadFile(SourceDir() / "robot/models/shadow_right.json")).get<retarget::Embodiment>();
  const auto returned = Json::parse(ReadFile(dir / "back/shadow_right.json")).get<retarget::Embodiment>();
  EXPECT_EQ(returned.side, "right");
  EXPECT_EQ(Json(returned.points), Json(original.points));

  const CommandResult bad = RunDoasido({"hand", "mirror", "shadow", "--out", (dir / "w").string(), "--axis", "w"});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--axis"), std::string::npos) << bad.err;
}

TEST(CliHand, UrdfAsHandAnswersWithTheImportCommand) {
  TempDir dir;
  const auto urdf = WriteTwoFingerHand(dir.path());
  const CommandResult r = RunDoasido(
      {"retarget-kinematic", "--hand", urdf.string(), "--keypoints",
       (SharedData() / "retarget/human_hand_keypoints_right.csv").string(), "--out", (dir / "out").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("doasido hand import --urdf " + urdf.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--hand " + (dir / "two_finger_hand/two_finger.json").string()), std::string::npos) << r.err;
}

}  // namespace
}  // namespace doasido::testing
