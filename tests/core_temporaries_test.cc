// Temporaries beside an output are removed only when they are doasido's
// (their marker says so) and their writer is gone; a person's file of the
// same shape, or a name whose "pid" cannot be one, is left alone and stops
// nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "core/error.h"
#include "core/whole_output.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::DeadPid;
using testing::TempDir;
using testing::WriteFile;

TEST(Temporaries, APersonsFilesOfTheShapeSurviveAWriter) {
  TempDir dir;
  // A person's thesis draft: the shape of our temporaries, a pid nobody
  // runs, no marker.
  WriteFile(dir / ".thesis.tmp-4000000-beef", "chapter one");
  // A pid with 20 digits: no pid at all (it used to stop every writer with
  // `error: stol`).
  WriteFile(dir / ".x.tmp-99999999999999999999-ab", "not ours either");
  // A marker with other contents proves nothing.
  const std::string forged = ".out.tmp-" + std::to_string(DeadPid()) + "-cafe";
  WriteFile(dir / forged, "forged");
  WriteFile(dir / (forged + ".doasido-temporary"), "something else\n");

  std::vector<fs::path> removed;
  WriteWhole(dir / "out", OutputKind::kFile,
             [](const fs::path& temp) { WriteFile(temp, "new"); }, &removed);
  EXPECT_EQ(ReadFile(dir / "out"), "new");
  EXPECT_TRUE(removed.empty());
  EXPECT_EQ(ReadFile(dir / ".thesis.tmp-4000000-beef"), "chapter one");
  EXPECT_EQ(ReadFile(dir / ".x.tmp-99999999999999999999-ab"), "not ours either");
  EXPECT_EQ(ReadFile(dir / forged), "forged");
  // Nothing of this write is left beside it: no temporary, no marker.
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    (void)e;
    ++entries;
  }
  EXPECT_EQ(entries, 5);
}

TEST(Temporaries, OursOfADeadWriterGoLiveOnesStay) {
  TempDir dir;
  // A killed export's folder temporary with its marker, and a marker whose
  // temporary was already renamed into place.
  const fs::path dead = dir / (".out.tmp-" + std::to_string(DeadPid()) + "-0badf00d");
  fs::create_directories(dead / "meta");
  MarkTemporary(dead);
  const fs::path orphan = dir / (".other.tmp-" + std::to_string(DeadPid()) + "-1234");
  MarkTemporary(orphan);
  // A temporary of a writer that runs (this process).
  const fs::path live = dir / (".out.tmp-" + std::to_string(getpid()) + "-abcd");
  WriteFile(live, "being written");
  MarkTemporary(live);

  const auto removed = RemoveAbandonedTemporaries(dir.path());
  ASSERT_EQ(removed.size(), 1u);
  EXPECT_EQ(removed[0], dead);
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_FALSE(fs::exists(dead.string() + ".doasido-temporary"));
  EXPECT_FALSE(fs::exists(orphan.string() + ".doasido-temporary"));
  EXPECT_EQ(ReadFile(live), "being written");
  EXPECT_TRUE(fs::exists(live.string() + ".doasido-temporary"));
}

TEST(Temporaries, PidsAreParsedNeverThrown) {
  EXPECT_EQ(ParsePid("4242"), 4242);
  EXPECT_FALSE(ParsePid("99999999999999999999"));
  EXPECT_FALSE(ParsePid("0"));
  EXPECT_FALSE(ParsePid(""));
  EXPECT_FALSE(ParsePid("12a"));
  EXPECT_FALSE(ParsePid("9999999999"));  // past pid_t
}

TEST(Temporaries, AFailedWriteLeavesTheEarlierOutputAndNoTrace) {
  TempDir dir;
  WriteFile(dir / "out", "earlier");
  EXPECT_THROW(WriteWhole(dir / "out", OutputKind::kFile,
                          [](const fs::path& temp) {
                            WriteFile(temp, "half");
                            throw Error("io", "disk full", {.file = temp.string()});
                          }),
               Error);
  EXPECT_EQ(ReadFile(dir / "out"), "earlier");
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    (void)e;
    ++entries;
  }
  EXPECT_EQ(entries, 1);
  // A writer that writes nothing does not put "nothing" in place.
  EXPECT_THROW(WriteWhole(dir / "out", OutputKind::kFile, [](const fs::path&) {}), Error);
  EXPECT_EQ(ReadFile(dir / "out"), "earlier");
}

}  // namespace
}  // namespace doasido
