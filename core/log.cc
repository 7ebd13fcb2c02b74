#include "core/log.h"

#include <spdlog/sinks/stdout_color_sinks.h>

namespace doasido {

void InitLogging(const std::string& level) {
  auto logger = spdlog::stderr_color_mt("doasido");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("%Y-%m-%d %H:%M:%S.%e %^%l%$ %v");
  spdlog::set_level(spdlog::level::from_str(level));
}

}  // namespace doasido
