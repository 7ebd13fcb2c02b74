// The one reader of a person's accept or reject, shared by the review page
// (a flagged run) and the verify page (a trajectory).
#include <gtest/gtest.h>

#include <string>

#include "core/error.h"
#include "review/request_body.h"

namespace doasido::review {
namespace {

// The field a refused body's error names.
std::string RefusedField(const Json& body) {
  try {
    ReadDecision(body);
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_request") << e.what();
    return e.site().field;
  }
  ADD_FAILURE() << "accepted: " << body.dump();
  return "";
}

TEST(ReadDecision, AcceptsAndComposesTheReason) {
  const Json body = {{"clip_id", 7},      {"stage", "interaction"}, {"decision", "reject"},
                     {"reviewer", "ana"}, {"reason_code", "no_hands"},
                     {"reason_text", std::string(600, 'x')}};
  const DecisionRequest d = ReadDecision(body);
  EXPECT_EQ(d.clip, 7);
  EXPECT_EQ(d.stage, "interaction");
  EXPECT_EQ(d.reviewer, "ana");
  EXPECT_FALSE(d.accept);
  EXPECT_EQ(d.reason, "no_hands: " + std::string(500, 'x'));  // the text cut at 500
  const DecisionRequest a = ReadDecision(
      {{"clip_id", 1}, {"stage", "retarget"}, {"decision", "accept"}, {"reviewer", "bo"}});
  EXPECT_TRUE(a.accept);
  EXPECT_EQ(a.reason, "");
}

TEST(ReadDecision, RefusesNamingTheField) {
  const Json good = {{"clip_id", 7}, {"stage", "interaction"}, {"decision", "accept"},
                     {"reviewer", "ana"}};
  Json b = good;
  b["decision"] = "maybe";
  EXPECT_EQ(RefusedField(b), "decision");
  b = good;
  b["reviewer"] = std::string(65, 'r');
  EXPECT_EQ(RefusedField(b), "reviewer");
  b = good;
  b.erase("reviewer");
  EXPECT_EQ(RefusedField(b), "reviewer");
  b = good;
  b["decision"] = "reject";  // a rejection without a reason code
  EXPECT_EQ(RefusedField(b), "reason_code");
  b = good;
  b["clip_id"] = 14.5;
  EXPECT_EQ(RefusedField(b), "clip_id");
}

}  // namespace
}  // namespace doasido::review
