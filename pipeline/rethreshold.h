// Re-thresholding: re-deciding the verdict stages from their stored
// measurements under new parameters, without decoding anything.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/config.h"
#include "db/database.h"

namespace doasido::pipeline {

struct RethresholdTally {
  std::int64_t redecided = 0, unchanged = 0, human_kept = 0, rerun = 0;
  std::int64_t downstream = 0;  // later runs queued again behind changed results
  // Clips sent back for a measurement they lack: a verdict that had made it
  // unnecessary (their not_measured runs name it) no longer rejects them.
  std::int64_t remeasure = 0;
  std::map<std::string, std::int64_t> transitions;  // "pass -> reject:no_activity"
};

// The stages of the database's pipeline that decide from stored
// measurements, in pipeline order; only those in `wanted` when it is not
// empty. Throws Error("bad_stage") for a wanted stage that is not one.
std::vector<std::string> RethresholdStages(Database& db, const std::vector<std::string>& wanted);

// Re-decides every finished run of `stage` under `config` and then runs, in
// process, the runs of `stage` that are pending (clips a change upstream
// sent on), each through RunClaimedStage. Verdicts given by a person are
// kept. A clip `stage` rejected and no longer rejects, whose other stages
// recorded not_measured naming `stage`, goes back to the stage that
// measures for them (filters_analyze: Database::Reset, its later runs
// dropped); nothing is decided from the measurement it lacks. With `dry_run` nothing is written and pending runs are not judged.
RethresholdTally RethresholdStage(Database& db, const std::string& stage, const Json& config,
                                  bool dry_run);

}  // namespace doasido::pipeline
