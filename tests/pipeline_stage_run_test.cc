// RunClaimedStage, the one path from a claim to a recorded result that the
// worker loop and re-thresholding share: results complete the run, any
// exception is a failed attempt (retried up to the limit, then failed with
// its message) unless its code is permanent (then failed at once), and a
// lost lease drops the result.
#include "pipeline/stage_run.h"

#include <gtest/gtest.h>

#include <map>
#include <stdexcept>

#include "core/error.h"
#include "core/error_codes.h"
#include "db/database.h"
#include "ingest/download.h"
#include "stages/probe_stage.h"
#include "stages/stage_registry.h"
#include "stages/stage_timeouts.h"
#include "tests/test_util.h"

namespace doasido::pipeline {
namespace {

using testing::TempDir;

// Passes clips whose external id is "good"; throws `Thrown` otherwise.
template <typename Thrown>
class PickyStage : public stages::Stage {
 public:
  std::string Name() const override { return "picky"; }
  Json Params() const override { return Json::object(); }
  StageResult Run(const ClipContext& context) override {
    if (context.clip.external_id != "good") throw Thrown("cannot judge " + context.clip.external_id);
    StageResult r;
    r.verdict = Verdict::kReject;
    r.reason = "picky";
    r.measurements = {{"seen", context.clip.id}};
    return r;
  }
};

// Throws Error(code) for every clip.
class FailingStage : public stages::Stage {
 public:
  explicit FailingStage(std::string code) : code_(std::move(code)) {}
  std::string Name() const override { return "picky"; }
  Json Params() const override { return Json::object(); }
  StageResult Run(const ClipContext& context) override {
    throw Error(code_, "fails every time", {.clip = context.clip.external_id});
  }

 private:
  std::string code_;
};

ClipId AddClip(Database& db, const std::string& name) {
  ClipRecord c;
  c.video_id = db.UpsertVideo("/videos/" + name + ".mp4");
  c.external_id = name;
  return db.InsertClip(c).id;
}

TEST(StageRun, ResultCompletesAndAnyExceptionIsAnAttempt) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"picky"});
  const ClipId good = AddClip(db, "good");
  const ClipId bad = AddClip(db, "bad");
  PickyStage<std::runtime_error> stage;  // not a doasido::Error: still recorded
  int failed = 0, done = 0;
  while (auto claim = db.ClaimNext("w", {}, kDefaultLeaseSeconds, kDefaultMaxAttempts)) {
    const StageRunReport r = RunClaimedStage(db, stage, *claim, "w", "h", kDefaultMaxAttempts);
    if (r.outcome == RunOutcome::kFailed) {
      ++failed;
      EXPECT_EQ(claim->clip_id, bad);
      EXPECT_NE(r.error.find("unexpected: cannot judge bad"), std::string::npos) << r.error;
    } else {
      ++done;
      EXPECT_EQ(r.outcome, RunOutcome::kDone);
      EXPECT_EQ(r.clip, "good");
    }
  }
  EXPECT_EQ(done, 1);
  EXPECT_EQ(failed, kDefaultMaxAttempts);
  const auto runs = db.ListRuns({.stage = "picky"});
  ASSERT_EQ(runs.size(), 2u);
  for (const auto& run : runs) {
    if (run.clip_id == good) {
      EXPECT_EQ(run.state, RunState::kDone);
      EXPECT_EQ(run.verdict, "reject");
      EXPECT_EQ((*db.GetMeasurements(good, "picky"))["seen"], good);
    } else {
      EXPECT_EQ(run.state, RunState::kFailed);
      EXPECT_EQ(run.attempts, kDefaultMaxAttempts);
      EXPECT_NE(run.error.find("cannot judge bad"), std::string::npos);
    }
  }
  // The stage wrote no file: no empty folder is left for either clip.
  EXPECT_FALSE(std::filesystem::exists(db.ArtifactDir(good, "picky")));
  EXPECT_FALSE(std::filesystem::exists(db.ArtifactDir(good, "picky").parent_path()));
  for (const auto& run : runs) {
    EXPECT_FALSE(std::filesystem::exists(db.ArtifactRoot() / std::to_string(run.clip_id)));
  }
}

// The error code alone decides (core/error_codes.h): a video the site says
// is gone fails at its first attempt, a rate limit spends every attempt.
TEST(StageRun, APermanentErrorIsNotRetriedAndATransientOneIs) {
  ASSERT_TRUE(IsPermanentError(kVideoUnavailable));
  ASSERT_FALSE(IsPermanentError("rate_limited"));
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"picky"});
  const ClipId gone = AddClip(db, "gone");
  const ClipId busy = AddClip(db, "busy");
  FailingStage permanent(kVideoUnavailable), transient("rate_limited");
  std::map<ClipId, int> tries;
  while (auto claim = db.ClaimNext("w", {}, kDefaultLeaseSeconds, kDefaultMaxAttempts)) {
    stages::Stage& stage = claim->clip_id == gone ? static_cast<stages::Stage&>(permanent) : transient;
    const StageRunReport r = RunClaimedStage(db, stage, *claim, "w", "h", kDefaultMaxAttempts);
    EXPECT_EQ(r.outcome, RunOutcome::kFailed);
    ++tries[claim->clip_id];
  }
  ASSERT_GT(kDefaultMaxAttempts, 1);
  EXPECT_EQ(tries[gone], 1);
  EXPECT_EQ(tries[busy], kDefaultMaxAttempts);
  for (const auto& run : db.ListRuns({.stage = "picky"})) {
    EXPECT_EQ(run.state, RunState::kFailed);
    EXPECT_EQ(run.attempts, run.clip_id == gone ? 1 : kDefaultMaxAttempts);
    EXPECT_NE(run.error.find(run.clip_id == gone ? kVideoUnavailable : "rate_limited"),
              std::string::npos)
        << run.error;
  }
}

// A timeout decides through the same table: the watchdog fails a run of a
// deterministic stage with a permanent code (once), a run of the network
// stage with a transient one (every attempt), by the registry's entry.
TEST(StageRun, ADeterministicStagesTimeoutIsNotRetriedAndTheDownloadsIs) {
  for (const auto& entry : stages::StageTable()) {
    EXPECT_EQ(IsPermanentError(stages::StageTimeoutCode(entry.name)), entry.deterministic) << entry.name;
  }
  EXPECT_STREQ(stages::StageTimeoutCode(stages::kProbeStageName), kStageTimeout);
  EXPECT_STREQ(stages::StageTimeoutCode(ingest::kDownloadStageName), kStageTimeoutTransient);
  EXPECT_STREQ(stages::StageTimeoutCode("no_such_stage"), kStageTimeout);
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"picky"});
  const ClipId probe = AddClip(db, "probe");
  const ClipId download = AddClip(db, "download");
  std::map<ClipId, int> tries;
  while (auto claim = db.ClaimNext("w", {}, kDefaultLeaseSeconds, kDefaultMaxAttempts)) {
    // What TimeOut records: Fail with the attempts AttemptsAllowed gives.
    const std::string stage =
        claim->clip_id == probe ? stages::kProbeStageName : ingest::kDownloadStageName;
    const int allowed = AttemptsAllowed(*claim, stages::StageTimeoutCode(stage), kDefaultMaxAttempts);
    ASSERT_TRUE(db.Fail(*claim, "w", std::string(stages::StageTimeoutCode(stage)) + ": " + stage, allowed));
    ++tries[claim->clip_id];
  }
  ASSERT_GT(kDefaultMaxAttempts, 1);
  EXPECT_EQ(tries[probe], 1);
  EXPECT_EQ(tries[download], kDefaultMaxAttempts);
  // An exception that is not an Error has no code: transient.
  Claim first{1, probe, "picky", 1};
  EXPECT_EQ(AttemptsAllowed(first, "", kDefaultMaxAttempts), kDefaultMaxAttempts);
  EXPECT_EQ(AttemptsAllowed(first, kVideoUnavailable, kDefaultMaxAttempts), 1);
}

TEST(StageRun, ALostLeaseDropsTheResultAndTheCommitHookStillRuns) {
  TempDir dir;
  Database db(dir / "q.db");
  db.SetPipeline({"picky"});
  AddClip(db, "good");
  const auto claim = db.ClaimNext("w", {}, kDefaultLeaseSeconds, kDefaultMaxAttempts);
  ASSERT_TRUE(claim);
  Claim stolen = *claim;
  PickyStage<std::runtime_error> stage;
  bool hook = false;
  const StageRunReport r =
      RunClaimedStage(db, stage, stolen, "not-the-owner", "h", kDefaultMaxAttempts,
                      [&] { hook = true; });
  EXPECT_EQ(r.outcome, RunOutcome::kLeaseLost);
  EXPECT_TRUE(hook);
  EXPECT_EQ(db.Summary().running, 1);
}

TEST(StageRun, EveryRegisteredStageIsNamedByItsEntryAndChecksItsDefaults) {
  for (const auto& entry : stages::StageTable()) {
    EXPECT_NO_THROW(entry.check(Json::object())) << entry.name;
    EXPECT_EQ(stages::MakeStage(entry.name, Json::object())->Name(), entry.name);
  }
  EXPECT_THROW(stages::CheckStageConfig(Json{{"activityy", Json::object()}}, {}), Error);
  EXPECT_THROW(stages::CheckStageConfig(Json{{"activity", {{"min_active_fraction", -0.1}}}}, {}), Error);
  EXPECT_NO_THROW(stages::CheckStageConfig(Json{{"report", Json::object()}}, {"report"}));
}

}  // namespace
}  // namespace doasido::pipeline
