#include "core/records.h"

#include "core/error.h"

namespace doasido {

const char* ToString(Verdict v) {
  switch (v) {
    case Verdict::kPass: return "pass";
    case Verdict::kReject: return "reject";
    case Verdict::kFlag: return "flag";
  }
  return "?";
}

Verdict VerdictFromString(const std::string& s) {
  if (s == "pass") return Verdict::kPass;
  if (s == "reject") return Verdict::kReject;
  if (s == "flag") return Verdict::kFlag;
  throw Error("bad_verdict", "verdict must be pass, reject or flag, not '" + s + "'");
}

}  // namespace doasido
