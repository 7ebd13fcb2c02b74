#include "pipeline/rethreshold.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <set>
#include <thread>

#include "stages/stage_registry.h"
#include "pipeline/stage_run.h"
#include "stages/verdict_stages.h"

namespace doasido::pipeline {
namespace {

// The measurements without the thresholds recorded beside each score: what
// later stages may read.
Json WithoutThresholds(Json measurements) {
  if (measurements.contains("summary") && measurements["summary"].is_object()) {
    measurements["summary"].erase("scores");
  }
  return measurements;
}

std::string Outcome(const std::string& verdict, const std::string& reason) {
  return reason.empty() ? verdict : verdict + ":" + reason;
}

bool HumanVerdict(Database& db, ClipId clip, const std::string& stage) {
  const auto history = db.VerdictHistory(clip, stage);
  return !history.empty() && history.back().source == kHumanVerdictSource;
}

// The clip goes back for the measurements that `stage`'s verdict had made
// unnecessary (now that it keeps the clip). Returns the stages re-queued.
std::int64_t Remeasure(Database& db, ClipId clip, const std::string& stage) {
  const std::set<std::string> measuring = stages::MeasuringStages(db, clip, stage);
  for (const std::string& by : measuring) db.Reset(by, clip);
  return static_cast<std::int64_t>(measuring.size());
}

// Re-decides the finished runs of `stage` (in batches of one transaction).
void RedecideFinished(Database& db, const stages::Stage& stage, const std::string& hash, bool dry_run,
                      RethresholdTally& tally) {
  const std::string name = stage.Name();
  const auto runs = db.ListRuns({.stage = name, .state = ToString(RunState::kDone)});
  constexpr size_t kBatch = 500;
  for (size_t begin = 0; begin < runs.size(); begin += kBatch) {
    Database::Transaction tx(db);
    for (size_t i = begin; i < std::min(runs.size(), begin + kBatch); ++i) {
      const StageRunRow& run = runs[i];
      const auto measurements = db.GetMeasurements(run.clip_id, name);
      if (!measurements) continue;
      const std::optional<StageResult> result = stage.Redecide(*measurements);
      if (!result) continue;
      const bool verdict_changed =
          run.verdict != ToString(result->verdict) || run.reason != result->reason;
      const bool changed = verdict_changed || WithoutThresholds(*measurements) !=
                                                  WithoutThresholds(result->measurements);
      std::int64_t requeued = 0;
      const bool kept = dry_run ? HumanVerdict(db, run.clip_id, name)
                                : !db.StoreRedecision(run.clip_id, name, hash, *result, changed,
                                                      &requeued);
      tally.downstream += requeued;
      if (!dry_run && !kept && run.verdict == ToString(Verdict::kReject) &&
          result->verdict != Verdict::kReject) {
        tally.remeasure += Remeasure(db, run.clip_id, name) > 0;
      }
      if (kept) {
        ++tally.human_kept;
        continue;
      }
      ++tally.redecided;
      if (verdict_changed) {
        ++tally.transitions[Outcome(run.verdict, run.reason) + " -> " +
                            Outcome(ToString(result->verdict), result->reason)];
      } else {
        ++tally.unchanged;
      }
    }
    if (!dry_run) tx.Commit();
  }
}

// After the last claimable run of `stage`: takes over the runs of dead
// processes of this machine (true: claim again), or, while another live
// process holds a run of it, says so once and waits for that lease (true);
// false when nothing of the stage is running.
bool WaitForLeases(Database& db, const std::string& stage, std::set<std::int64_t>& told) {
  const auto dead = db.ExpireDeadLeases();
  for (const Database::Lease& l : dead) {
    std::fprintf(stderr, "taking over clip %lld's %s run %lld: %s is gone\n",
                 static_cast<long long>(l.clip_id), l.stage.c_str(),
                 static_cast<long long>(l.run_id), l.owner.c_str());
  }
  if (!dead.empty()) return true;
  const auto live = db.LiveLeases({stage});
  if (live.empty()) return false;
  const Database::Lease& l = live.front();
  if (told.insert(l.run_id).second) {
    std::fprintf(stderr,
                 "waiting for clip %lld's %s run %lld: leased by %s for %.0f s more (a live "
                 "process; taken over when the lease ends)\n",
                 static_cast<long long>(l.clip_id), l.stage.c_str(),
                 static_cast<long long>(l.run_id), l.owner.c_str(), std::max(0.0, l.expires - Now()));
  }
  std::this_thread::sleep_for(std::chrono::seconds(1));
  return true;
}

}  // namespace

std::vector<std::string> RethresholdStages(Database& db, const std::vector<std::string>& wanted) {
  std::vector<std::string> names;
  for (const auto& stage : db.Pipeline()) {
    bool eligible = false;
    for (const auto& entry : stages::StageTable()) {
      if (entry.name == stage) eligible = entry.decides_from_measurements;
    }
    const bool asked =
        wanted.empty() || std::find(wanted.begin(), wanted.end(), stage) != wanted.end();
    if (eligible && asked) names.push_back(stage);
  }
  for (const auto& name : wanted) {
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      throw Error("bad_stage",
                  "'" + name + "' is not a pipeline stage that decides from measurements",
                  {.file = db.path().string(), .field = "stages"});
    }
  }
  return names;
}

RethresholdTally RethresholdStage(Database& db, const std::string& name, const Json& config,
                                  bool dry_run) {
  RethresholdTally tally;
  const auto stage = stages::MakeStage(name, config);
  const std::string hash = stages::ResultHash(*stage);
  RedecideFinished(db, *stage, hash, dry_run, tally);
  if (dry_run) return tally;
  // Claims like a worker (its lease names this process), so a re-run after
  // a kill takes the killed run's claims over at once.
  const std::string worker = Database::LeaseOwner(getpid(), getpid());
  std::set<std::int64_t> told;
  for (;;) {
    if (auto claim = db.ClaimNext(worker, {name}, kDefaultLeaseSeconds, kDefaultMaxAttempts)) {
      const StageRunReport report =
          RunClaimedStage(db, *stage, *claim, worker, hash, kDefaultMaxAttempts);
      if (report.outcome != RunOutcome::kDone) continue;
      ++tally.transitions["(queued) -> " +
                          Outcome(ToString(report.result.verdict), report.result.reason)];
      ++tally.rerun;
      continue;
    }
    if (!WaitForLeases(db, name, told)) break;
  }
  return tally;
}

}  // namespace doasido::pipeline
