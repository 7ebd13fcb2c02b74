// Signs of life of the stage run in this process, read by the worker's
// watch (pipeline/worker.cc). A stage that gets on calls
// ReportStageProgress(): the decoder per frame, a model command whenever its
// log grows, every Progress bar step. Once a run has reported progress, the
// watch renews its lease only while the count keeps moving: a run whose
// count stands still for longer than [timeouts] no_progress is failed as a
// stage timeout. A run that never reports is held to its wall-clock limit
// alone (stages/stage_timeouts.h).
#pragma once

#include <cstdint>

namespace doasido {

// Cheap (one relaxed atomic add); safe from any thread.
void ReportStageProgress();

// Monotonic count of ReportStageProgress() calls in this process.
std::uint64_t StageProgressCount();

}  // namespace doasido
