// HTTP byte ranges (RFC 9110 §14) for serving video files to a <video>
// element, which seeks by asking for `Range: bytes=first-` and expects
// 206 Partial Content with Content-Range.
#pragma once

#include <cstdint>
#include <string>

namespace doasido::review {

enum class RangeKind {
  kWhole,          // no usable Range header: send the whole file with 200
  kPartial,        // send bytes [first, last] with 206
  kUnsatisfiable,  // send 416 with Content-Range: bytes */size
};

struct RangeDecision {
  RangeKind kind = RangeKind::kWhole;
  std::uint64_t first = 0;
  std::uint64_t last = 0;  // inclusive
};

// Decides how to answer `range_header` (the Range value, empty when absent)
// for a file of `size` bytes. A single `bytes=a-b`, `bytes=a-` or
// `bytes=-suffix` range is served, its end clamped to the file; a range
// starting at or past the end, a zero suffix, a reversed range or a
// malformed bytes range is unsatisfiable. Other units and multi-range
// requests are answered with the whole file, which RFC 9110 allows.
RangeDecision DecideRange(const std::string& range_header, std::uint64_t size);

// "bytes first-last/size".
std::string ContentRange(const RangeDecision& range, std::uint64_t size);

}  // namespace doasido::review
