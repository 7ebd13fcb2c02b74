// `doasido retarget-kinematic` on the first 20 frames of the real keypoint
// CSV, and on a malformed CSV.
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/test_util.h"

namespace doasido {
namespace {

using doasido::testing::ReadFile;
using doasido::testing::RunDoasido;
using doasido::testing::SharedData;
using doasido::testing::TempDir;
using doasido::testing::WriteFile;

TEST(CliRetarget, WritesATrajectoryForEachFrame) {
  TempDir dir;
  std::istringstream in(ReadFile(SharedData() / "retarget/human_hand_keypoints_right.csv"));
  std::string line, head;
  for (int i = 0; i < 21 && std::getline(in, line); ++i) head += line + "\n";
  WriteFile(dir / "k.csv", head);
  const auto r = RunDoasido({"retarget-kinematic", "--hand", "sharpa_right", "--keypoints",
                             (dir / "k.csv").string(), "--out", (dir / "out").string(),
                             "--robots-dir", (SharedData() / "robots").string(), "--restarts", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, ::testing::HasSubstr("sharpa_right: 20 frames"));
  const std::string csv = ReadFile(dir / "out/trajectory.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 21);
  EXPECT_THAT(csv, ::testing::StartsWith("frame,time,valid,fingertip_error,doasido_wrist_x"));
}

TEST(CliRetarget, MalformedCsvNamesFileAndLine) {
  TempDir dir;
  WriteFile(dir / "bad.csv", "k0_x,k0_y,k0_z\n1,2\n");
  const auto r = RunDoasido({"retarget-kinematic", "--keypoints", (dir / "bad.csv").string(),
                             "--out", (dir / "out").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, ::testing::HasSubstr("bad.csv:2"));
}

}  // namespace
}  // namespace doasido
