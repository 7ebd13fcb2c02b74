// Parsing JSON that comes from outside (clip lists, bundles, configs, review
// requests) with limits. nlohmann::json parses and frees nested values
// recursively: a document 100,000 levels deep overflows the stack and kills
// the process. ParseJsonInput measures the depth first, without recursion,
// and refuses what is too deep or too large with a named error.
#pragma once

#include <cstddef>
#include <string_view>

#include "core/config.h"
#include "core/error.h"

namespace doasido {

struct JsonLimits {
  int max_depth = 64;                          // nested arrays/objects
  std::size_t max_bytes = 256u * 1024 * 1024;  // of text
};

// Error codes: kJsonTooDeep, kJsonTooLarge and kBadJson ("not JSON").
inline constexpr const char* kJsonTooDeep = "json_too_deep";
inline constexpr const char* kJsonTooLarge = "json_too_large";
inline constexpr const char* kBadJson = "bad_json";

// The deepest nesting of arrays and objects in `text` (brackets inside
// strings do not count). Stops counting past `stop_at`.
int JsonDepth(std::string_view text, int stop_at);

// Parses `text`, or throws Error(kJsonTooLarge / kJsonTooDeep / kBadJson)
// with `site` and a message saying the limit or where the syntax broke.
Json ParseJsonInput(std::string_view text, const ErrorSite& site = {}, const JsonLimits& limits = {});

}  // namespace doasido
