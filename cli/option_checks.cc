#include "cli/option_checks.h"

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace doasido::cli {

CLI::Validator FiniteRange(double lo, double hi) {
  std::ostringstream range;
  range << "in [" << lo << ", " << hi << "]";
  const std::string description = "NUMBER " + range.str();
  return CLI::Validator(
      [lo, hi, in = range.str()](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || end == nullptr || *end != '\0') return "'" + text + "' is not a number";
        if (!std::isfinite(v)) return "'" + text + "' is not a finite number";
        if (v < lo || v > hi) return "'" + text + "' is not " + in;
        return "";
      },
      description);
}

}  // namespace doasido::cli
