// Wall-clock limits of stage runs. Every stage has a default that fits its
// work (seconds for probe, an hour for a model command); the [timeouts]
// section of the config overrides them by stage name:
//
//   [timeouts]
//   probe = 30          # seconds
//   bundle = 7200
//   no_progress = 900   # a run that reported progress and then stands still
//
// A run past its limit is failed as kStageTimeout (core/error_codes.h) by
// the worker's watchdog, which then ends the worker process (a hung read or
// a stuck library call cannot be cancelled in place); the supervisor starts
// another worker. The timeout of a deterministic stage is permanent (its
// code, StageTimeoutCode, decides through core/error_codes.h).
// `no_progress` applies to every stage run that reports progress
// (core/stage_progress.h): once its count stands still that long, the watch
// stops renewing its lease and fails it the same way.
#pragma once

#include <string>

#include "core/config.h"

namespace doasido::stages {

inline constexpr const char* kTimeoutsSection = "timeouts";
inline constexpr const char* kNoProgressKey = "no_progress";
inline constexpr double kDefaultNoProgressSeconds = 900;

// Throws Error("bad_config") naming timeouts.<key> for a key that is not a
// stage or a limit that is not a number of seconds in (0, 30 days].
void CheckStageTimeouts(const Json& config);

// The limit of `stage` in seconds: the config's, else the stage's default.
double StageTimeout(const Json& config, const std::string& stage);

// The error code of a timed-out run of `stage`: kStageTimeout (permanent)
// for a deterministic stage and for a name the registry does not know,
// kStageTimeoutTransient (retried) for one that is not
// (StageEntry::deterministic).
const char* StageTimeoutCode(const std::string& stage);

// How long a run that reports progress may stand still: the config's
// timeouts.no_progress, else kDefaultNoProgressSeconds.
double NoProgressLimit(const Json& config);

}  // namespace doasido::stages
