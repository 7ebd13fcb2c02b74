#include "core/test_pause.h"

#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>

namespace doasido {

void TestPause(std::string_view point) {
  const char* spec = std::getenv(kTestPauseVariable);
  if (spec == nullptr) return;
  const std::string text = spec;
  size_t begin = 0;
  while (begin < text.size()) {
    const size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    const size_t eq = item.find('=');
    if (eq != std::string::npos && item.compare(0, eq, point) == 0 && eq == point.size()) {
      const long ms = std::strtol(item.c_str() + eq + 1, nullptr, 10);
      if (ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(ms));
      return;
    }
    begin = end + 1;
  }
}

}  // namespace doasido
