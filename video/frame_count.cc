#include "video/frame_count.h"

#include <algorithm>
#include <cmath>

namespace doasido {

std::int64_t MissingFramesAllowed(std::int64_t declared) {
  if (declared <= 0) return 0;
  const auto fraction =
      static_cast<std::int64_t>(std::ceil(kMissingFramesFraction * static_cast<double>(declared)));
  return std::max(kMissingFramesMin, fraction);
}

}  // namespace doasido
