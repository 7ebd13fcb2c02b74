// How the `retarget` stage's ladder of sampler presets spent its time
// (retarget/dynamic/sampler_ladder.h): how many clips were simulated and
// succeeded, and per rung how many clips it ran on, how many succeeded
// there, how many kept its run, and its wall seconds. A clip retargeted
// without simulation (hand-only: the kinematic trajectory kept) counts
// apart, as it ran no rung.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "db/database.h"
#include "reports/run_stats.h"

namespace doasido::reports {

struct RungStats {
  std::string rung;
  std::int64_t ran = 0;        // clips this rung ran on
  std::int64_t succeeded = 0;  // of those, the ones it succeeded on
  std::int64_t kept = 0;       // clips whose kept run is this rung's
  DurationStats seconds;       // its wall seconds per clip
};

struct RetargetLadderStats {
  std::int64_t simulated = 0;      // clips whose retarget run simulated (ran rungs)
  std::int64_t succeeded = 0;      // of those, the ones whose kept run succeeded
  std::int64_t not_simulated = 0;  // done without a rung (hand-only, or rejected first)
  std::vector<RungStats> rungs;    // in ladder order (the order clips ran them)
  bool empty() const { return simulated == 0 && not_simulated == 0; }
  Json ToJson() const;
};

// From the measurements of every done `retarget` run in `runs`; measurements
// written before the ladder recorded its rungs (no "rungs" list) count as
// simulated when they hold a success metric, under no rung.
RetargetLadderStats ComputeRetargetLadder(Database& db,
                                          const std::vector<Database::ReportRun>& runs);

}  // namespace doasido::reports
