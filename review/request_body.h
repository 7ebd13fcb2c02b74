// Reading what a browser (or anyone on the port) sends to the review API:
// bodies with size and depth limits, ids that are whole numbers in range.
// Each throws doasido::Error, which the server answers with 400 (or 404 for
// an id no row can have), naming the field and the value.
#pragma once

#include <cstdint>
#include <string>

#include "core/config.h"

namespace doasido::review {

// The largest id SQLite rows get here and JSON numbers hold exactly.
inline constexpr std::int64_t kMaxId = (std::int64_t{1} << 53) - 1;

// A JSON object of at most 64 KiB and 8 levels; else Error("bad_request").
Json ParseRequestBody(const std::string& body);

// body[key] as an id: a JSON integer in [1, kMaxId]. 14.7, "14", 1e30, -3
// and true are refused with Error("bad_request") naming the key and value.
std::int64_t RequireId(const Json& body, const char* key);

// The id in a URL's (\d+) group; Error("no_such_id") past kMaxId.
std::int64_t PathId(const std::string& digits);

// A person's accept or reject, as the review page (a flagged run) and the
// verify page (a trajectory) post it.
struct DecisionRequest {
  std::int64_t clip = 0;
  std::string stage;
  std::string reviewer;  // 1-64 characters
  bool accept = false;
  // reason_code, then ": " and the first 500 characters of reason_text;
  // a rejection always has a code.
  std::string reason;
};

// body's clip_id, stage, decision ("accept" or "reject"), reviewer,
// reason_code and reason_text, checked; Error("bad_request") naming the
// field otherwise.
DecisionRequest ReadDecision(const Json& body);

}  // namespace doasido::review
