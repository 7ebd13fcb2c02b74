// A stage that only waits: the queue's own diagnostic, used to test and
// benchmark claiming, leases and crash recovery without any media work.
// It records which worker ran it and passes every clip.
#pragma once

#include <string>

#include "stages/stage.h"

namespace doasido::stages {

inline constexpr const char* kNoopStageName = "noop";

struct NoopConfig {
  double work_ms = 0;  // time each clip takes
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(NoopConfig, work_ms)

// work_ms in [0, 1 hour].
void CheckConfig(const NoopConfig& c, const std::string& section);

class NoopStage : public Stage {
 public:
  explicit NoopStage(NoopConfig config = {}) : config_(config) {}
  std::string Name() const override { return kNoopStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;

 private:
  NoopConfig config_;
};

}  // namespace doasido::stages
