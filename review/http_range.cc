#include "review/http_range.h"

#include <algorithm>
#include <cctype>
#include <optional>

namespace doasido::review {
namespace {

std::string Trim(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

// A run of decimal digits that fits 64 bits; nullopt otherwise.
std::optional<std::uint64_t> ParseNumber(const std::string& s) {
  if (s.empty() || s.size() > 19) return std::nullopt;
  std::uint64_t v = 0;
  for (char c : s) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
    v = v * 10 + static_cast<std::uint64_t>(c - '0');
  }
  return v;
}

}  // namespace

RangeDecision DecideRange(const std::string& range_header, std::uint64_t size) {
  const RangeDecision whole{RangeKind::kWhole, 0, size == 0 ? 0 : size - 1};
  const RangeDecision unsatisfiable{RangeKind::kUnsatisfiable, 0, 0};
  const std::string header = Trim(range_header);
  if (header.empty()) return whole;
  const std::string unit = "bytes=";
  if (header.compare(0, unit.size(), unit) != 0) return whole;
  const std::string spec = Trim(header.substr(unit.size()));
  if (spec.find(',') != std::string::npos) return whole;
  const size_t dash = spec.find('-');
  if (dash == std::string::npos) return unsatisfiable;
  const std::string a = Trim(spec.substr(0, dash));
  const std::string b = Trim(spec.substr(dash + 1));
  if (a.empty()) {  // suffix: the last b bytes
    const auto suffix = ParseNumber(b);
    if (!suffix || *suffix == 0 || size == 0) return unsatisfiable;
    const std::uint64_t n = std::min(*suffix, size);
    return {RangeKind::kPartial, size - n, size - 1};
  }
  const auto first = ParseNumber(a);
  if (!first || *first >= size) return unsatisfiable;
  std::uint64_t last = size - 1;
  if (!b.empty()) {
    const auto end = ParseNumber(b);
    if (!end || *end < *first) return unsatisfiable;
    last = std::min(*end, size - 1);
  }
  return {RangeKind::kPartial, *first, last};
}

std::string ContentRange(const RangeDecision& range, std::uint64_t size) {
  if (range.kind == RangeKind::kUnsatisfiable) return "bytes */" + std::to_string(size);
  return "bytes " + std::to_string(range.first) + "-" + std::to_string(range.last) + "/" +
         std::to_string(size);
}

}  // namespace doasido::review
