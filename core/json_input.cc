#include "core/json_input.h"

#include <string>

namespace doasido {

int JsonDepth(std::string_view text, int stop_at) {
  int depth = 0, deepest = 0;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > deepest) deepest = depth;
      if (deepest > stop_at) return deepest;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return deepest;
}

Json ParseJsonInput(std::string_view text, const ErrorSite& site, const JsonLimits& limits) {
  if (text.size() > limits.max_bytes) {
    throw Error(kJsonTooLarge,
                std::to_string(text.size()) + " bytes of JSON, more than the limit of " +
                    std::to_string(limits.max_bytes),
                site);
  }
  if (JsonDepth(text, limits.max_depth) > limits.max_depth) {
    throw Error(kJsonTooDeep,
                "JSON nested deeper than " + std::to_string(limits.max_depth) + " levels", site);
  }
  try {
    return Json::parse(text);
  } catch (const Json::exception& e) {
    // parse_error, and out_of_range for a number past double's range
    // (1e400), which is no more JSON a reader here can use.
    throw Error(kBadJson, std::string("not JSON: ") + e.what(), site);
  }
}

}  // namespace doasido
