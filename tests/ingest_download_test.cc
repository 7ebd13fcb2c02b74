// Pieces of the download stage in process: site ids, hosts, the command
// template's failure names and their permanence, reuse of a finished file,
// and the per-host slot limit.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "core/error_codes.h"
#include "ingest/download_command.h"
#include "stages/download_stage.h"
#include "ingest/host_slots.h"
#include "ingest/http_fetch.h"
#include "tests/test_util.h"

namespace doasido::ingest {
namespace {

using testing::ReadFile;
using testing::SharedData;
using testing::TempDir;
using testing::WriteFile;

TEST(DownloadPieces, YoutubeIdsFromEveryUrlFormAndHashesForOthers) {
  for (const std::string url :
       {"https://www.youtube.com/watch?v=dQw4w9WgXcQ",
        "https://youtube.com/watch?feature=x&v=dQw4w9WgXcQ",
        "https://youtu.be/dQw4w9WgXcQ?t=3", "https://www.youtube.com/shorts/dQw4w9WgXcQ",
        "https://www.youtube.com/embed/dQw4w9WgXcQ", "https://m.youtube.com/watch?v=dQw4w9WgXcQ"}) {
    EXPECT_EQ(VideoIdOf(url), "dQw4w9WgXcQ") << url;
  }
  const std::string other = VideoIdOf("https://example.org/a.mp4");
  EXPECT_EQ(other.size(), 16u);
  EXPECT_NE(other, VideoIdOf("https://example.org/b.mp4"));
  const std::string not_an_id = "https://www.youtube.com/watch?v=short";
  EXPECT_EQ(VideoIdOf(not_an_id), ParamHash(not_an_id));
  EXPECT_EQ(UrlHost("https://user:pw@Example.ORG:8080/x?y"), "example.org");
  EXPECT_EQ(UrlHost("http://[::1]:80/v"), "[::1]");
  EXPECT_EQ(UrlHost("/local/file.mp4"), "");
  EXPECT_EQ(LastLines("a\n\nb\r\nc\n", 2), "b | c");
}

// Runs the template `script` and returns the error code it was named by,
// and whether it was permanent; "" for success.
std::pair<std::string, bool> Outcome(const TempDir& dir, const std::string& script) {
  WriteFile(dir / "s.sh", script);
  const DownloadCommand command{"sh '" + (dir / "s.sh").string() + "' {url} {output} {id}",
                                "b[height<={max_height}]", 480};
  try {
    RunDownloadCommand(command, "https://youtu.be/abcdefghijk", dir / "out" / "v.mp4",
                       dir / "log.txt");
  } catch (const Error& e) {
    return {e.code(), IsPermanentError(e.code())};
  }
  return {"", false};
}

TEST(DownloadPieces, CommandFailuresAreNamedAndOnlyTransientOnesRetried) {
  TempDir dir;
  using O = std::pair<std::string, bool>;
  EXPECT_EQ(Outcome(dir, "echo x > \"$2\"\n"), O("", false));
  EXPECT_EQ(Outcome(dir, "exit 10\n"), O("video_unavailable", true));
  EXPECT_EQ(Outcome(dir, "echo 'ERROR: [youtube] x: Private video' >&2; exit 1\n"),
            O("video_unavailable", true));
  EXPECT_EQ(Outcome(dir, "exit 11\n"), O("geo_blocked", true));
  EXPECT_EQ(Outcome(dir, "echo 'The uploader has not made this video available in your "
                         "country' >&2; exit 1\n"),
            O("geo_blocked", true));
  EXPECT_EQ(Outcome(dir, "exit 12\n"), O("rate_limited", false));
  EXPECT_EQ(Outcome(dir, "echo 'ERROR: HTTP Error 429: Too Many Requests' >&2; exit 1\n"),
            O("rate_limited", false));
  EXPECT_EQ(Outcome(dir, "exit 0\n"), O("download_failed", false));  // no file written
  EXPECT_EQ(Outcome(dir, "exit 2\n"), O("download_failed", false));
  // The placeholders arrive as single shell words.
  WriteFile(dir / "args.sh", "printf '%s\\n' \"$@\" > \"$3\"\n");
  const DownloadCommand command{
      "sh '" + (dir / "args.sh").string() + "' {format} {max_height} {output} {id}",
      "b[height<={max_height}]", 480};
  RunDownloadCommand(command, "https://youtu.be/abcdefghijk", dir / "o" / "x y.mp4",
                     dir / "log.txt");
  EXPECT_EQ(ReadFile(dir / "o" / "x y.mp4"), "b[height<=480]\n480\n" +
                                                 (dir / "o" / "x y.mp4").string() +
                                                 "\nabcdefghijk\n");
}

TEST(DownloadPieces, AFinishedDownloadIsReusedWithItsChecksum) {
  TempDir dir;
  const auto video = SharedData() / "videos" / "bass_guitar.mp4";
  WriteFile(dir / "copy.sh", "cp '" + video.string() + "' \"$1\"; echo copied >> '" +
                                 (dir / "calls").string() + "'\n");
  DownloadConfig config;
  config.command = "sh '" + (dir / "copy.sh").string() + "' {output}";
  const auto first = DownloadVideo("https://www.youtube.com/watch?v=abcdefghijk", dir / "media",
                                   dir / "logs", config);
  EXPECT_EQ(first.summary.source, "command");
  EXPECT_EQ(first.path, dir / "media" / "youtube" / "abcdefghijk.mp4");
  EXPECT_EQ(first.summary.size_bytes, static_cast<std::int64_t>(std::filesystem::file_size(video)));
  EXPECT_EQ(first.sha256.size(), 64u);
  const auto second =
      DownloadVideo("https://youtu.be/abcdefghijk", dir / "media", dir / "logs", config);
  EXPECT_EQ(second.summary.source, "reused");
  EXPECT_EQ(second.summary.bytes, 0);
  EXPECT_EQ(second.sha256, first.sha256);
  EXPECT_EQ(ReadFile(dir / "calls"), "copied\n");
  // A file whose sidecar disagrees with it is fetched again.
  WriteFile(first.path, "truncated");
  EXPECT_EQ(DownloadVideo("https://youtu.be/abcdefghijk", dir / "media", dir / "logs", config)
                .summary.source,
            "command");
  EXPECT_EQ(ReadFile(dir / "calls"), "copied\ncopied\n");
}

TEST(DownloadPieces, AHostSlotIsHeldByOneHolderAtATime) {
  TempDir dir;
  std::atomic<bool> released{false};
  auto first = std::make_unique<HostSlot>(dir.path(), "example.org", 1);
  std::thread waiter([&] {
    HostSlot second(dir.path(), "example.org", 1);
    EXPECT_TRUE(released.load()) << "got the only slot while it was held";
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  released = true;
  first.reset();
  waiter.join();
  // Another host, or a second slot, is free at once.
  HostSlot other(dir.path(), "example.com", 1);
  HostSlot a(dir.path(), "example.org", 2), b(dir.path(), "example.org", 2);
  EXPECT_NE(a.index(), b.index());
}

TEST(DownloadPieces, ConfigOutOfRangeIsRefused) {
  DownloadConfig c;
  c.max_per_host = 0;
  EXPECT_THROW(stages::DownloadStage{c}, Error);
  c = DownloadConfig();
  c.low_speed_time_s = 0;
  EXPECT_THROW(stages::DownloadStage{c}, Error);
}

}  // namespace
}  // namespace doasido::ingest
