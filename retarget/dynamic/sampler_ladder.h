// A per-clip ladder of sampler settings (rungs): a clip is retargeted at the
// cheapest rung first and re-run at the next rung only when it does not
// succeed (retarget_metrics.h: E_pos < 0.1 m and E_rot < 0.5 rad against
// the reference); the best run is kept (a success, else the smallest error
// relative to the thresholds). The cost is the cheap rung plus the
// failures' share; success is at least the best single rung's on every
// clip the rungs would each decide the same way.
#pragma once

#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "core/config.h"
#include "retarget/dynamic/annealed_sampler.h"
#include "retarget/dynamic/retarget_metrics.h"
#include "robot/trajectory/format.h"

namespace doasido::retarget {

// DynamicRetargetConfig::preset running its `ladder`, and the rung name
// standing for its `sampler` table as written.
inline constexpr const char* kLadderPreset = "ladder";
inline constexpr const char* kSamplerRung = "sampler";

// The ladder's measurement keys are in robot/trajectory/format.h (the
// report reads them).

struct RungOutcome {
  std::string name;
  double seconds = 0;  // wall time of the rung's whole run
  TrackingMetrics metrics;
};

// Whether `a` is a better result than `b`: a success beats a failure; else
// the smaller e_pos / kSuccessPosition + e_rot / kSuccessRotation (NaN worst).
bool BetterTracking(const TrackingMetrics& a, const TrackingMetrics& b);

template <class Run>
struct LadderResult {
  Run best;                       // the kept run
  int best_rung = -1;             // its index in `rungs`
  std::vector<RungOutcome> rungs; // every rung that ran, in order
};

// Runs `track(name)` for the rungs in order until one succeeds
// (Run::metrics.success); keeps the best. `rungs` must not be empty.
template <class Run>
LadderResult<Run> RunLadder(const std::vector<std::string>& rungs,
                            const std::function<Run(const std::string& rung)>& track) {
  LadderResult<Run> out;
  for (size_t i = 0; i < rungs.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    Run run = track(rungs[i]);
    RungOutcome rung{rungs[i], std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                     run.metrics};
    out.rungs.push_back(rung);
    if (out.best_rung < 0 || BetterTracking(run.metrics, out.best.metrics)) {
      out.best = std::move(run);
      out.best_rung = static_cast<int>(i);
    }
    if (rung.metrics.success) break;
  }
  return out;
}

// The ladder's measurements (keys above) into `m`.
void WriteLadderMeasurements(const std::vector<RungOutcome>& rungs, int best_rung, Json& m);

}  // namespace doasido::retarget
