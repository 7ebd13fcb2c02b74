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

}  // namespace doasido::review
