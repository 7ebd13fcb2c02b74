#include "core/records.h"

#include "core/error.h"

namespace doasido {

const char* ToString(Verdict v) {
  switch (v) {
    case Verdict::kPass: return "pass";
    case Verdict::kReject: return "reject";
    case Verdict::kFlag: return "flag";
    case Verdict::kNotMeasured: return "not_measured";
  }
  return "?";
}

Verdict VerdictFromString(const std::string& s) {
  if (s == "pass") return Verdict::kPass;
  if (s == "reject") return Verdict::kReject;
  if (s == "flag") return Verdict::kFlag;
  if (s == "not_measured") return Verdict::kNotMeasured;
  throw Error("bad_verdict",
              "verdict must be pass, reject, flag or not_measured, not '" + s + "'");
}

}  // namespace doasido
