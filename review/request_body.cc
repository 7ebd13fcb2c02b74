#include "review/request_body.h"

#include <charconv>

#include "core/error.h"
#include "core/json_input.h"

namespace doasido::review {

Json ParseRequestBody(const std::string& body) {
  Json j;
  try {
    j = ParseJsonInput(body, {}, {.max_depth = 8, .max_bytes = 64u << 10});
  } catch (const Error& e) {
    throw Error("bad_request", e.code() + ": " + e.message());
  }
  if (!j.is_object()) throw Error("bad_request", "the request body is not a JSON object");
  return j;
}

std::int64_t RequireId(const Json& body, const char* key) {
  if (!body.contains(key)) throw Error("bad_request", "missing", {.field = key});
  const Json& v = body.at(key);
  const bool whole = v.is_number_integer() &&
                     (v.is_number_unsigned() ? v.get<std::uint64_t>() >= 1 &&
                                                   v.get<std::uint64_t>() <= kMaxId
                                             : v.get<std::int64_t>() >= 1 &&
                                                   v.get<std::int64_t>() <= kMaxId);
  if (!whole) {
    throw Error("bad_request",
                "an id is a whole number from 1 to " + std::to_string(kMaxId) + ", not " + v.dump(),
                {.field = key});
  }
  return v.get<std::int64_t>();
}

std::int64_t PathId(const std::string& digits) {
  std::int64_t id = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), id);
  if (ec != std::errc() || end != digits.data() + digits.size() || id < 1 || id > kMaxId) {
    throw Error("no_such_id", "no row has the id " + digits.substr(0, 40));
  }
  return id;
}

DecisionRequest ReadDecision(const Json& body) {
  DecisionRequest d;
  d.clip = RequireId(body, "clip_id");
  d.stage = body.at("stage").get<std::string>();
  const std::string decision = body.at("decision").get<std::string>();
  d.reviewer = body.value("reviewer", std::string());
  const std::string code = body.value("reason_code", std::string());
  const std::string text = body.value("reason_text", std::string());
  if (decision != "accept" && decision != "reject") {
    throw Error("bad_request", "must be accept or reject", {.field = "decision"});
  }
  if (d.reviewer.empty() || d.reviewer.size() > 64) {
    throw Error("bad_request", "a reviewer name (1-64 characters) is required",
                {.field = "reviewer"});
  }
  d.accept = decision == "accept";
  if (!d.accept && code.empty()) {
    throw Error("bad_request", "a rejection needs a reason code", {.field = "reason_code"});
  }
  d.reason = code;
  if (!text.empty()) d.reason += (d.reason.empty() ? "" : ": ") + text.substr(0, 500);
  return d;
}

}  // namespace doasido::review
