#include "core/stage_progress.h"

#include <atomic>

namespace doasido {
namespace {

std::atomic<std::uint64_t> g_count{0};

}  // namespace

void ReportStageProgress() { g_count.fetch_add(1, std::memory_order_relaxed); }

std::uint64_t StageProgressCount() { return g_count.load(std::memory_order_relaxed); }

}  // namespace doasido
