// The one rule for frame counts that probe and every decode share: the
// count is what the file holds, and a whole file may end a little short of
// the count its container declares (containers round it; phone recordings
// often declare one or two frames more than decode, while ffmpeg decodes
// every packet without error). A shorter file is truncated or corrupt, a
// deterministic failure (kVideoTruncated, permanent: no retry).
#pragma once

#include <cstdint>

#include "core/error_codes.h"  // kVideoTruncated

namespace doasido {

inline constexpr double kMissingFramesFraction = 0.02;
inline constexpr std::int64_t kMissingFramesMin = 2;

// Frames a whole file may lack against `declared` (0: unknown, nothing lacks):
// max(2, ceil(2% of declared)).
std::int64_t MissingFramesAllowed(std::int64_t declared);

}  // namespace doasido
