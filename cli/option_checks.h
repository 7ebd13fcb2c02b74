// Range checks for numeric command-line options. CLI11's own Range lets NaN
// through (every comparison with NaN is false) and "inf" parses as a
// double, so every numeric option of doasido goes through FiniteRange.
#pragma once

#include <CLI/CLI.hpp>

namespace doasido::cli {

// Worker processes a command may start: far above any useful value on one
// machine, low enough that a typo does not fork thousands of processes.
inline constexpr int kMaxJobs = 256;
// The shortest lease: the watch thread renews a lease every third of it and
// wakes every 0.2 s, so a shorter lease would expire under a live worker.
inline constexpr double kMinLeaseSeconds = 1.0;

// Accepts a number in [lo, hi] that is finite; the error names the range.
CLI::Validator FiniteRange(double lo, double hi);

}  // namespace doasido::cli
