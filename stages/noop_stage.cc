#include "stages/noop_stage.h"

#include <unistd.h>

#include <chrono>
#include <thread>

#include "core/config_check.h"

namespace doasido::stages {

void CheckConfig(const NoopConfig& c, const std::string& section) {
  RequireInRange(section, "work_ms", c.work_ms, 0, 3600e3);
}

StageResult NoopStage::Run(const ClipContext& context) {
  if (config_.work_ms > 0) {
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(config_.work_ms));
  }
  StageResult result;
  result.measurements = {{"pid", static_cast<int>(getpid())}, {"clip", context.clip.id}};
  return result;
}

}  // namespace doasido::stages
