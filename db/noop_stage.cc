#include "db/noop_stage.h"

#include <unistd.h>

#include <chrono>
#include <thread>

namespace doasido {

StageResult NoopStage::Run(const ClipContext& context) {
  if (config_.work_ms > 0) {
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(config_.work_ms));
  }
  StageResult result;
  result.measurements = {{"pid", static_cast<int>(getpid())}, {"clip", context.clip.id}};
  return result;
}

}  // namespace doasido
