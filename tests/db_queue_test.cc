// The stage queue: claims, leases, attempts, parameter hashes, verdicts and
// relocation, against a real SQLite file.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <thread>

#include "db/database.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::TempDir;

ClipId AddClip(Database& db, const std::string& video, std::int64_t start, std::int64_t end) {
  ClipRecord clip;
  clip.video_id = db.UpsertVideo(video);
  clip.start_frame = start;
  clip.end_frame = end;
  return db.InsertClip(clip).id;
}

TEST(DbQueue, NewDatabaseHasLatestSchemaAndReopens) {
  TempDir dir;
  {
    Database db(dir / "a.db");
    EXPECT_EQ(db.SchemaVersion(), Database::LatestSchemaVersion());
    db.SetPipeline({"probe", "noop"});
  }
  Database again(dir / "a.db");
  EXPECT_EQ(again.SchemaVersion(), Database::LatestSchemaVersion());
  EXPECT_EQ(again.Pipeline(), (std::vector<std::string>{"probe", "noop"}));
}

TEST(DbQueue, RefusesNewerSchema) {
  TempDir dir;
  { Database db(dir / "a.db"); }
  // Simulate a database written by a newer doasido.
  sqlite3* raw = nullptr;
  sqlite3_open((dir / "a.db").c_str(), &raw);
  sqlite3_exec(raw, "UPDATE schema_version SET version = 999", nullptr, nullptr, nullptr);
  sqlite3_close(raw);
  try {
    Database db(dir / "a.db");
    FAIL() << "opened a newer schema";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("newer"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("a.db"), std::string::npos) << e.what();
  }
}

TEST(DbQueue, SameVideoAndSpanIsTheSameClip) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"noop"});
  const ClipId a = AddClip(db, "/videos/a.mp4", 0, 10);
  ClipRecord same;
  same.video_id = db.UpsertVideo("/videos/a.mp4");
  same.start_frame = 0;
  same.end_frame = 10;
  const auto again = db.InsertClip(same);
  EXPECT_FALSE(again.inserted);
  EXPECT_EQ(again.id, a);
  ClipRecord whole;  // no span: a different clip of the same video
  whole.video_id = same.video_id;
  EXPECT_TRUE(db.InsertClip(whole).inserted);
  EXPECT_EQ(db.CountClips(), 2);
  EXPECT_EQ(db.Summary().pending, 2);
}

TEST(DbQueue, ClipAdvancesThroughStagesOnlyWhenItPasses) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a", "b"});
  const ClipId pass = AddClip(db, "/v.mp4", 0, 1);
  const ClipId reject = AddClip(db, "/v.mp4", 2, 3);
  for (int i = 0; i < 2; ++i) {
    const auto claim = db.ClaimNext("w", {}, 60, 3);
    ASSERT_TRUE(claim);
    EXPECT_EQ(claim->stage, "a");
    StageResult result;
    result.verdict = claim->clip_id == pass ? Verdict::kPass : Verdict::kReject;
    result.reason = claim->clip_id == pass ? "" : "too_dark";
    result.measurements = {{"brightness", claim->clip_id == pass ? 100 : 3}};
    ASSERT_TRUE(db.Complete(*claim, "w", "h1", result, 0.1));
  }
  const auto next = db.ClaimNext("w", {}, 60, 3);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->clip_id, pass);
  EXPECT_EQ(next->stage, "b");
  EXPECT_FALSE(db.ClaimNext("w", {}, 60, 3)) << "rejected clip must not enter stage b";
  const auto m = db.GetMeasurements(reject, "a");
  ASSERT_TRUE(m);
  EXPECT_EQ((*m)["brightness"], 3);
  // Stage b sees stage a's measurements, not its own.
  const auto context = db.LoadContext(pass, "b");
  EXPECT_EQ(context.measurements.count("a"), 1u);
  EXPECT_EQ(context.measurements.at("a")["brightness"], 100);
}

// Runs every claimable stage, giving the verdict `decide` names for each
// (clip, stage); returns the stages run, in order, as "clip:stage".
template <typename F>
std::vector<std::string> RunAll(Database& db, F decide) {
  std::vector<std::string> ran;
  while (const auto claim = db.ClaimNext("w", {}, 60, 3)) {
    StageResult result;
    result.verdict = decide(claim->clip_id, claim->stage);
    if (result.verdict != Verdict::kPass) result.reason = "why_" + claim->stage;
    EXPECT_TRUE(db.Complete(*claim, "w", "h", result, 0.1));
    ran.push_back(std::to_string(claim->clip_id) + ":" + claim->stage);
  }
  return ran;
}

// Filters a, b, c (a flag at a or b lets the clip go on), then d past them.
TEST(DbQueue, AFlagDoesNotStopTheFiltersAndWaitsForAPersonBeforeTheNextStage) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a", "b", "c", "d"}, {"a", "b"});
  const ClipId flagged = AddClip(db, "/v.mp4", 0, 1);        // flag at a, pass after
  const ClipId rejected_later = AddClip(db, "/v.mp4", 2, 3); // flag at a, reject at b
  const ClipId clean = AddClip(db, "/v.mp4", 4, 5);          // passes everything
  const auto ran = RunAll(db, [&](ClipId clip, const std::string& stage) {
    if (stage == "a" && clip != clean) return Verdict::kFlag;
    if (stage == "b" && clip == rejected_later) return Verdict::kReject;
    return Verdict::kPass;
  });
  const auto count = [&](ClipId clip, const std::string& stage) {
    return std::count(ran.begin(), ran.end(), std::to_string(clip) + ":" + stage);
  };
  // The flagged clip was judged by every filter but went no further.
  EXPECT_EQ(count(flagged, "b"), 1);
  EXPECT_EQ(count(flagged, "c"), 1);
  EXPECT_EQ(count(flagged, "d"), 0);
  EXPECT_EQ(count(rejected_later, "b"), 1);
  EXPECT_EQ(count(rejected_later, "c"), 0);
  EXPECT_EQ(count(clean, "d"), 1);
  // Only the clip no later filter rejected waits for a person.
  const auto waiting = db.ListFlagged();
  ASSERT_EQ(waiting.size(), 1u);
  EXPECT_EQ(waiting[0].clip_id, flagged);
  EXPECT_EQ(waiting[0].stage, "a");
  EXPECT_EQ(db.CountFlagged(), 1);
  // A person's accept lets it go on past the filters.
  db.RecordReview(flagged, "a", "ann", true, "");
  EXPECT_EQ(RunAll(db, [](ClipId, const std::string&) { return Verdict::kPass; }),
            (std::vector<std::string>{std::to_string(flagged) + ":d"}));
  EXPECT_EQ(db.CountFlagged(), 0);
}

TEST(DbQueue, TwoFlagsNeedTwoAcceptsAndAFlagWhereFlagsStopStillStops) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a", "b", "c"}, {"a"});
  const ClipId clip = AddClip(db, "/v.mp4", 0, 1);
  const auto ran = RunAll(db, [](ClipId, const std::string& stage) {
    return stage == "c" ? Verdict::kPass : Verdict::kFlag;
  });
  // b's flag stops (b is not in the set): c never ran.
  EXPECT_EQ(ran.size(), 2u);
  EXPECT_EQ(db.ListFlagged().size(), 2u);
  db.RecordReview(clip, "a", "ann", true, "");
  EXPECT_FALSE(db.ClaimNext("w", {}, 60, 3)) << "b's flag still waits";
  db.RecordReview(clip, "b", "ann", true, "");
  const auto next = db.ClaimNext("w", {}, 60, 3);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->stage, "c");
}

TEST(DbQueue, ExpiredLeaseIsReclaimedAndTheOldOwnerCannotComplete) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a"});
  AddClip(db, "/v.mp4", 0, 1);
  const auto first = db.ClaimNext("dead", {}, 0.05, 5);
  ASSERT_TRUE(first);
  EXPECT_FALSE(db.ClaimNext("other", {}, 60, 5)) << "lease still held";
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const auto second = db.ClaimNext("other", {}, 60, 5);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->run_id, first->run_id);
  EXPECT_EQ(second->attempts, 2);
  EXPECT_FALSE(db.Complete(*first, "dead", "h", StageResult{}, 0)) << "stale owner completed";
  EXPECT_TRUE(db.Complete(*second, "other", "h", StageResult{}, 0));
  EXPECT_EQ(db.DoneEventCounts().size(), 1u);
  EXPECT_EQ(db.Summary().done, 1);
}

TEST(DbQueue, HeartbeatKeepsTheLease) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a"});
  AddClip(db, "/v.mp4", 0, 1);
  const auto claim = db.ClaimNext("w", {}, 0.2, 3);
  ASSERT_TRUE(claim);
  for (int i = 0; i < 4; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    ASSERT_TRUE(db.Heartbeat(claim->run_id, "w", 0.2));
    EXPECT_FALSE(db.ClaimNext("thief", {}, 60, 3));
  }
  EXPECT_FALSE(db.Heartbeat(claim->run_id, "thief", 0.2));
}

TEST(DbQueue, FailuresRetryUpToTheLimitThenFailWithTheError) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a"});
  const ClipId clip = AddClip(db, "/v.mp4", 0, 1);
  for (int attempt = 1; attempt <= 3; ++attempt) {
    const auto claim = db.ClaimNext("w", {}, 60, 3);
    ASSERT_TRUE(claim) << attempt;
    EXPECT_EQ(claim->attempts, attempt);
    db.Fail(*claim, "w", "video_truncated: decoded 3 of 300 frames", 3);
  }
  EXPECT_FALSE(db.ClaimNext("w", {}, 60, 3));
  const auto runs = db.ListRuns({.state = "failed"});
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].clip_id, clip);
  EXPECT_NE(runs[0].error.find("video_truncated"), std::string::npos);
  EXPECT_EQ(db.Retry("", std::nullopt), 1);
  EXPECT_TRUE(db.ClaimNext("w", {}, 60, 3));
}

TEST(DbQueue, LeaseExpiringTooOftenFailsTheRun) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a"});
  AddClip(db, "/v.mp4", 0, 1);
  for (int i = 0; i < 2; ++i) {
    ASSERT_TRUE(db.ClaimNext("w" + std::to_string(i), {}, 0.01, 2));
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
  }
  EXPECT_FALSE(db.ClaimNext("w", {}, 60, 2));
  const auto failed = db.ListRuns({.state = "failed"});
  ASSERT_EQ(failed.size(), 1u);
  EXPECT_NE(failed[0].error.find("lease expired"), std::string::npos) << failed[0].error;
}

TEST(DbQueue, SameParametersAreANoOpNewParametersRerun) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a"});
  AddClip(db, "/v.mp4", 0, 1);
  const auto claim = db.ClaimNext("w", {}, 60, 3);
  ASSERT_TRUE(db.Complete(*claim, "w", "hash1", StageResult{}, 0));
  EXPECT_EQ(db.InvalidateOtherParams("a", "hash1"), 0);
  EXPECT_FALSE(db.ClaimNext("w", {}, 60, 3));
  EXPECT_EQ(db.InvalidateOtherParams("a", "hash2"), 1);
  EXPECT_TRUE(db.ClaimNext("w", {}, 60, 3));
}

TEST(DbQueue, HumanVerdictMovesTheClipOn) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a", "b"});
  const ClipId clip = AddClip(db, "/v.mp4", 0, 1);
  auto claim = db.ClaimNext("w", {}, 60, 3);
  StageResult flagged;
  flagged.verdict = Verdict::kFlag;
  flagged.reason = "unsure";
  ASSERT_TRUE(db.Complete(*claim, "w", "h", flagged, 0));
  EXPECT_FALSE(db.ClaimNext("w", {}, 60, 3)) << "flagged clips wait for a person";
  db.SetVerdict(clip, "a", Verdict::kPass, "looks fine", "human");
  claim = db.ClaimNext("w", {}, 60, 3);
  ASSERT_TRUE(claim);
  EXPECT_EQ(claim->stage, "b");
  // Rejecting it afterwards drops the queued later stage.
  db.SetVerdict(clip, "a", Verdict::kReject, "blurry", "human");
  EXPECT_EQ(db.ListRuns({.stage = "b"}).size(), 0u);
}

TEST(DbQueue, ResetRequeuesAndDropsLaterStages) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a", "b"});
  AddClip(db, "/v.mp4", 0, 1);
  auto claim = db.ClaimNext("w", {}, 60, 3);
  ASSERT_TRUE(db.Complete(*claim, "w", "h", StageResult{}, 0));
  EXPECT_EQ(db.ListRuns({.stage = "b"}).size(), 1u);
  EXPECT_EQ(db.Reset("a", std::nullopt), 1);
  EXPECT_EQ(db.ListRuns({.stage = "b"}).size(), 0u);
  claim = db.ClaimNext("w", {}, 60, 3);
  ASSERT_TRUE(claim);
  EXPECT_EQ(claim->stage, "a");
  EXPECT_EQ(claim->attempts, 1);
}

TEST(DbQueue, PipelineMayOnlyGrowOnceRunsExist) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"a"});
  AddClip(db, "/v.mp4", 0, 1);
  EXPECT_NO_THROW(db.SetPipeline({"a", "b"}));
  EXPECT_THROW(db.SetPipeline({"b"}), Error);
}

TEST(DbQueue, DatabaseFolderIsRelocatable) {
  TempDir dir;
  const auto folder = dir / "project";
  std::filesystem::create_directories(folder / "videos");
  testing::WriteFile(folder / "videos" / "a.mp4", "x");
  ClipId clip = 0;
  {
    Database db(folder / "q.db");
    db.SetPipeline({"a"});
    clip = AddClip(db, (folder / "videos" / "a.mp4").string(), 0, 1);
    AddClip(db, "https://example.org/b.mp4", 0, 1);
  }
  const auto moved = dir / "moved";
  std::filesystem::rename(folder, moved);
  Database db(moved / "q.db");
  const auto video = db.GetVideo(db.GetClip(clip).video_id);
  EXPECT_EQ(video.path, (moved / "videos" / "a.mp4").string());
  EXPECT_TRUE(std::filesystem::exists(video.path));
  EXPECT_EQ(db.Resolve("https://example.org/b.mp4"), "https://example.org/b.mp4");
}

}  // namespace
}  // namespace doasido
