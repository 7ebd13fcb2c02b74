// The labelled real footage (testing/real_footage.h): the committed table
// reads, its clips exist where it says (../shared/data and the files of the
// Debian packages scripts/setup.sh installs) and lie inside their videos,
// and the split follows its documented rule.
#include "testing/real_footage.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <set>

#include "core/error.h"
#include "core/file_text.h"
#include "tests/test_util.h"
#include "video/probe.h"

namespace doasido::testing {
namespace {

const std::set<std::string> kFilters = {"shot_boundary", "interaction", "out_of_frame",
                                        "activity", "camera_motion"};

std::filesystem::path Table() { return SourceDir() / "bench" / "real_footage_labels.tsv"; }

TEST(RealFootage, TheTableHasFortyClipsLabelledPerFilterInTwoNearlyEqualHalves) {
  const std::vector<RealFootageClip> clips = ReadRealFootage(Table());
  ASSERT_GE(clips.size(), 40u);
  std::map<Half, int> per_half;
  std::map<std::string, Half> half_of_video;
  for (const RealFootageClip& clip : clips) {
    per_half[clip.half]++;
    EXPECT_FALSE(clip.labels.empty()) << clip.id << " has no label";
    for (const auto& [filter, label] : clip.labels) EXPECT_EQ(kFilters.count(filter), 1u) << filter;
    // Spans of one video never straddle the halves.
    const auto [it, fresh] = half_of_video.emplace(clip.source, clip.half);
    EXPECT_EQ(it->second, clip.half) << clip.id;
    // The 12 videos tuned on before the split are all in the tuning half.
    if (clip.source.rfind("shared:videos/", 0) == 0) {
      EXPECT_EQ(clip.half, Half::kTuning) << clip.id;
    }
  }
  // A held-back half in name only proves nothing: the halves stay within a
  // few clips of each other (clips are added to the smaller one, the rule
  // never changes).
  EXPECT_GE(per_half[Half::kHeldBack], 20);
  EXPECT_LE(std::abs(per_half[Half::kTuning] - per_half[Half::kHeldBack]), 4)
      << per_half[Half::kTuning] << " tuning, " << per_half[Half::kHeldBack] << " held back";
}

TEST(RealFootage, EveryClipIsThereAndInsideItsVideo) {
  TempDir cache;
  for (const RealFootageClip& clip : ReadRealFootage(Table())) {
    const std::filesystem::path video = ResolveRealFootage(clip.source, SharedData(), cache.path());
    const VideoInfo info = video::ProbeVideo(video);
    EXPECT_LT(clip.first_frame, info.frame_count) << clip.id;
    EXPECT_LT(clip.last_frame, info.frame_count) << clip.id;
  }
}

TEST(RealFootage, TheSplitIsTheFirstByteOfTheNamesSha256) {
  // sha256("cup.mp4") = b1..., sha256("box.mp4") = 0c... (sha256sum).
  EXPECT_EQ(SplitHalf("/usr/share/doc/opencv-doc/opencv4/html/cup.mp4.gz"), Half::kHeldBack);
  EXPECT_EQ(SplitHalf("/elsewhere/cup.mp4"), Half::kHeldBack);
  EXPECT_EQ(SplitHalf("/usr/share/doc/opencv-doc/opencv4/html/box.mp4.gz"), Half::kTuning);
  // sha256("diver.mov") = 0d..., sha256("pens.mp4") = 49... (odd: held back).
  EXPECT_EQ(SplitHalf("/usr/share/doc/pd-extendedview/media/diver.mov"), Half::kHeldBack);
  EXPECT_EQ(SplitHalf("/usr/share/doc/docutils-doc/docs/user/rst/images/pens.mp4.gz"),
            Half::kHeldBack);
  // sha256("cockatoo.mp4") = 7b... (odd) but the tuned-on folder decides first.
  EXPECT_EQ(SplitHalf("shared:retarget/cockatoo.mp4"), Half::kHeldBack);
  EXPECT_EQ(SplitHalf("shared:videos/cockatoo.mp4"), Half::kTuning);
}

TEST(RealFootage, AGzippedVideoIsReadDecompressed) {
  TempDir dir;
  const std::string bytes(100000, 'v');
  gzFile out = gzopen((dir / "clip.mp4.gz").c_str(), "wb");
  ASSERT_NE(out, nullptr);
  ASSERT_EQ(gzwrite(out, bytes.data(), static_cast<unsigned>(bytes.size())),
            static_cast<int>(bytes.size()));
  gzclose(out);
  const std::filesystem::path video =
      ResolveRealFootage((dir / "clip.mp4.gz").string(), SharedData(), dir / "cache");
  EXPECT_EQ(video, dir / "cache" / "clip.mp4");
  EXPECT_EQ(ReadFileOrThrow(video, "io", "cannot read"), bytes);
  EXPECT_EQ(ResolveRealFootage("shared:videos/apple.mp4", SharedData(), dir / "cache"),
            SharedData() / "videos" / "apple.mp4");
}

TEST(RealFootage, AMissingPackageFileNamesItselfAndTheSetup) {
  try {
    ResolveRealFootage("/usr/share/no-such-package/clip.avi", SharedData(), "/tmp");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.site().file, "/usr/share/no-such-package/clip.avi");
    EXPECT_NE(e.message().find("scripts/setup.sh"), std::string::npos) << e.what();
  }
}

TEST(RealFootage, BadRowsAreRefusedNamingLineAndField) {
  TempDir dir;
  const std::string header =
      "# a comment\nid\tsource\tfirst\tlast\tinteraction\tshot_boundary\torigin\twhat\n";
  struct Case {
    std::string row, field;
  } cases[] = {
      {"a\tshared:x.mp4\t0\t-1\tmaybe\tpass\to\tw\n", "interaction"},
      {"a\tshared:x.mp4\t0\t-1\ttrimmed\tpass\to\tw\n", "interaction"},  // shots only
      {"a\tshared:x.mp4\tten\t-1\tpass\tpass\to\tw\n", "first"},
      {"a\tshared:x.mp4\t9\t3\tpass\tpass\to\tw\n", "last"},
      {"a\tshared:x.mp4\t0\t-1\tpass\tpass\to\tw\na\tshared:y.mp4\t0\t-1\tpass\tpass\to\tw\n", "id"},
  };
  for (const Case& c : cases) {
    const std::filesystem::path table = dir / "labels.tsv";
    std::ofstream(table) << header << c.row;
    try {
      ReadRealFootage(table);
      ADD_FAILURE() << "accepted: " << c.row;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), kBadLabels);
      EXPECT_EQ(e.site().file, table.string());
      EXPECT_GE(e.site().line, 3);
      EXPECT_EQ(e.site().field, c.field) << e.what();
    }
  }
  std::ofstream(dir / "good.tsv") << header << "a\tshared:x.mp4\t5\t9\t-\ttrimmed\to\tw\n";
  const std::vector<RealFootageClip> clips = ReadRealFootage(dir / "good.tsv");
  ASSERT_EQ(clips.size(), 1u);
  EXPECT_EQ(clips[0].first_frame, 5);
  EXPECT_EQ(clips[0].last_frame, 9);
  EXPECT_EQ(clips[0].labels, (std::map<std::string, std::string>{{"shot_boundary", "trimmed"}}));
}

}  // namespace
}  // namespace doasido::testing
