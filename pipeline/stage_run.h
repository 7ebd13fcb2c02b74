// One claimed stage run, start to finish: the single place that runs a stage
// on a clip and records the outcome, shared by the worker loop and by
// re-thresholding so both handle errors, attempts and leases alike.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include "db/database.h"
#include "stages/stage.h"

namespace doasido::pipeline {

// Queue limits every claimant uses unless told otherwise.
inline constexpr double kDefaultLeaseSeconds = 60;  // a dead worker's run is reclaimed after this
inline constexpr int kDefaultMaxAttempts = 3;       // attempts before a run is marked failed

enum class RunOutcome { kDone, kFailed, kLeaseLost };

struct StageRunReport {
  RunOutcome outcome = RunOutcome::kDone;
  StageResult result;   // when done
  std::string error;    // when failed: "code: message [site]" or "unexpected: ..."
  std::string clip;     // external id, or the clip id
  double seconds = 0;   // time spent in the stage
};

// Loads the clip's context, creates its artifact folder, runs `stage` on it
// and records the outcome in one transaction: Complete (with `param_hash`)
// or, when the stage threw, Fail (back to pending until `max_attempts`).
// doasido::Error and any other std::exception count as a failed attempt; an
// Error whose code a retry cannot fix (IsPermanentError, core/error_codes.h)
// fails the run at once.
// `in_same_commit` (may be empty) runs inside that transaction after the
// record, so a worker can claim its next run in the same commit.
StageRunReport RunClaimedStage(Database& db, stages::Stage& stage, const Claim& claim,
                               const std::string& worker, const std::string& param_hash,
                               int max_attempts,
                               const std::function<void()>& in_same_commit = {});

// The one rule of what is retried, for a run and for the watchdog's timeout:
// the attempts `claim` may have after failing with error `code` ("" for an
// exception that is not an Error): its current attempt when a retry cannot
// fix the error (IsPermanentError), else `max_attempts`.
int AttemptsAllowed(const Claim& claim, std::string_view code, int max_attempts);

}  // namespace doasido::pipeline
