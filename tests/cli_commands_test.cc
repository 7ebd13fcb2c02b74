// The doasido commands end to end, as a user runs them.
#include <gtest/gtest.h>

#include "db/database.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::RunDoasido;
using testing::SharedData;
using testing::TempDir;
using testing::WriteFile;

TEST(Commands, EveryCommandHasHelpWithAnExample) {
  const auto top = RunDoasido({"--help"});
  EXPECT_EQ(top.exit_code, 0);
  for (const std::string cmd :
       {"init", "ingest", "status", "queue", "worker", "run", "rethreshold", "report", "review"}) {
    const auto r = RunDoasido({cmd, "--help"});
    EXPECT_EQ(r.exit_code, 0) << cmd;
    EXPECT_NE(r.out.find("Example"), std::string::npos) << cmd << " --help has no example";
    EXPECT_NE(top.out.find(cmd), std::string::npos) << cmd << " missing from doasido --help";
  }
}

TEST(Commands, RunProbesRealVideosAndATruncatedOneFailsWithItsName) {
  TempDir dir;
  const std::string bytes = testing::ReadFile(SharedData() / "videos" / "03_blocks.mp4");
  WriteFile(dir / "broken.mp4", bytes.substr(0, bytes.size() / 3));
  const auto v = SharedData() / "videos";
  WriteFile(dir / "clips.csv",
            "video,id,start_frame,end_frame,source\n" + (v / "02_cups.mp4").string() +
                ",cups,0,299,internet\n" + (v / "apple.mp4").string() +
                ",apple,,,internet\n" + (v / "bedroom.mp4").string() +
                ",bed_too_long,0,500,egocentric\n" + "broken.mp4,broken,0,10,internet\n");
  const std::string db = (dir / "work" / "d.db").string();
  ASSERT_EQ(RunDoasido({"init", "--db", db, "--pipeline", "probe"}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", db, (dir / "clips.csv").string(),
                               "--max-attempts", "2"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("probe"), std::string::npos) << run.out;

  const auto status = RunDoasido({"status", "--db", db, "--json"});
  ASSERT_EQ(status.exit_code, 0);
  const Json j = Json::parse(status.out);
  EXPECT_EQ(j["clips"], 4);
  std::map<std::string, long> by_outcome;
  for (const auto& c : j["counts"]) {
    by_outcome[c["state"].get<std::string>() + "/" + c["verdict"].get<std::string>() + "/" +
               c["reason"].get<std::string>()] += c["count"].get<long>();
  }
  EXPECT_EQ(by_outcome["done/pass/"], 2);
  EXPECT_EQ(by_outcome["done/reject/span_outside_video"], 1);
  EXPECT_EQ(by_outcome["failed//"], 1);

  const auto failed = RunDoasido({"queue", "list", "--db", db, "--state", "failed", "--json"});
  const Json rows = Json::parse(failed.out);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0]["external_id"], "broken");
  const std::string error = rows[0]["error"];
  EXPECT_NE(error.find("broken.mp4"), std::string::npos) << error;
  EXPECT_NE(error.find("clip broken"), std::string::npos) << error;
  // A truncated file stays truncated: failed at the first attempt of the two allowed.
  EXPECT_EQ(rows[0]["attempts"], 1);

  // The probe recorded the true facts of a real video.
  Database check(db);
  const auto video = check.GetVideo(check.GetClip(1).video_id);
  ASSERT_TRUE(video.info);
  EXPECT_EQ(video.info->frame_count, 300);
  EXPECT_EQ(video.info->width, 1280);

  // Running again is a no-op; retry gives the failed clip another go.
  const auto again = RunDoasido({"run", "--db", db});
  EXPECT_EQ(again.exit_code, 0);
  EXPECT_EQ(check.Summary().done, 3);
  const auto retry = RunDoasido({"queue", "retry", "--db", db});
  EXPECT_NE(retry.out.find("1 failed runs queued again"), std::string::npos) << retry.out;
  EXPECT_EQ(check.Summary().pending, 1);
  const auto reset = RunDoasido({"queue", "reset", "--db", db, "--stage", "probe", "--all"});
  EXPECT_EQ(reset.exit_code, 0);
  EXPECT_EQ(check.Summary().pending, 4);
}

TEST(Commands, ChangedParametersRerunSameParametersDoNot) {
  TempDir dir;
  const std::string db = (dir / "d.db").string();
  WriteFile(dir / "l.csv", "url,id\nhttps://example.org/a.mp4,a\nhttps://example.org/b.mp4,b\n");
  ASSERT_EQ(RunDoasido({"init", "--db", db, "--pipeline", "noop"}).exit_code, 0);
  ASSERT_EQ(RunDoasido({"run", "--db", db, (dir / "l.csv").string()}).exit_code, 0);
  Database check(db);
  auto completions = [&check] {
    int n = 0;
    for (const auto& [key, count] : check.DoneEventCounts()) n += count;
    return n;
  };
  EXPECT_EQ(completions(), 2);
  ASSERT_EQ(RunDoasido({"run", "--db", db}).exit_code, 0);
  EXPECT_EQ(completions(), 2) << "same parameters must be a no-op";
  WriteFile(dir / "p.toml", "[noop]\nwork_ms = 1\n");
  ASSERT_EQ(RunDoasido({"run", "--db", db, "--config", (dir / "p.toml").string()}).exit_code, 0);
  EXPECT_EQ(completions(), 4) << "new parameters must run every clip again";
  ASSERT_EQ(RunDoasido({"run", "--db", db, "--config", (dir / "p.toml").string()}).exit_code, 0);
  EXPECT_EQ(completions(), 4);
  EXPECT_EQ(check.Summary().done, 2);
  WriteFile(dir / "bad.toml", "[noop]\nwork_sm = 1\n");
  const auto bad = RunDoasido({"run", "--db", db, "--config", (dir / "bad.toml").string()});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("noop.work_sm"), std::string::npos) << bad.err;
}

// A list option takes one value (comma-separated) and leaves the clip list
// after it a positional: `run --stages noop l.csv` once read l.csv as a stage.
TEST(Commands, AStageListBeforeTheClipListLeavesTheClipList) {
  TempDir dir;
  const std::string db = (dir / "d.db").string();
  WriteFile(dir / "l.csv", "url,id\nhttps://example.org/a.mp4,a\nhttps://example.org/b.mp4,b\n");
  ASSERT_EQ(RunDoasido({"init", "--db", db, "--pipeline", "noop"}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", db, "--stages", "noop", (dir / "l.csv").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(Database(db).Summary().done, 2);
}

TEST(Commands, ClearErrorsForBadInvocations) {
  TempDir dir;
  const auto missing = RunDoasido({"ingest", "--db", (dir / "d.db").string(),
                                   (dir / "none.csv").string()});
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.err.find("none.csv"), std::string::npos) << missing.err;
  const auto unknown = RunDoasido({"init", "--db", (dir / "d.db").string(), "--pipeline", "nope"});
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.err.find("no stage 'nope'"), std::string::npos) << unknown.err;
  const auto nodir = RunDoasido({"status", "--db", "/no/such/folder/d.db"});
  EXPECT_NE(nodir.exit_code, 0);
  EXPECT_NE(nodir.err.find("/no/such/folder"), std::string::npos) << nodir.err;
}

}  // namespace
}  // namespace doasido
