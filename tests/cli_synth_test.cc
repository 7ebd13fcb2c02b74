// `doasido synth` end to end: files written, help text, and a clear error
// for a bad mix.
#include <gtest/gtest.h>

#include "tests/test_util.h"

namespace doasido::testing {
namespace {

TEST(CliSynth, WritesADatasetAndRejectsABadMix) {
  TempDir dir;
  const CommandResult ok = RunDoasido({"synth", "--out", (dir / "out").string(), "--clips", "2",
                                       "--seed", "3", "--frames", "24", "--width", "160",
                                       "--height", "120", "--mix", "clean=1,static=1"});
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_NE(ok.out.find("2 clips"), std::string::npos) << ok.out;
  for (const char* f :
       {"clips.csv", "summary.json", "videos/s3c0000.mp4", "videos/s3c0001.mp4", "gt/s3c0000.json",
        "bundles/s3c0001/meta.json", "Annotations/synth_v_s3c0000_frame000023.xml"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / f)) << f;
  }
  const CommandResult bad =
      RunDoasido({"synth", "--out", (dir / "bad").string(), "--clips", "1", "--mix", "bogus=1"});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("mix"), std::string::npos) << bad.err;
  const CommandResult help = RunDoasido({"synth", "--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("Example"), std::string::npos);
}

}  // namespace
}  // namespace doasido::testing
