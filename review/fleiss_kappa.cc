#include "review/fleiss_kappa.h"

#include <cmath>
#include <limits>

#include "core/error.h"

namespace doasido::review {

FleissKappaResult FleissKappa(const std::vector<std::vector<int>>& counts) {
  if (counts.empty() || counts[0].empty()) {
    throw Error("bad_table", "Fleiss' kappa needs at least one subject and one category",
                {.field = "counts"});
  }
  FleissKappaResult r;
  r.subjects = static_cast<int>(counts.size());
  r.categories = static_cast<int>(counts[0].size());
  for (int c : counts[0]) r.raters += c;
  for (size_t i = 0; i < counts.size(); ++i) {
    const auto& row = counts[i];
    int sum = 0;
    for (int c : row) {
      if (c < 0) {
        throw Error("bad_table", "negative count in subject " + std::to_string(i),
                    {.field = "counts"});
      }
      sum += c;
    }
    if (static_cast<int>(row.size()) != r.categories || sum != r.raters) {
      throw Error("bad_table",
                  "subject " + std::to_string(i) + " has " + std::to_string(row.size()) +
                      " categories and " + std::to_string(sum) + " ratings; subject 0 has " +
                      std::to_string(r.categories) + " and " + std::to_string(r.raters),
                  {.field = "counts"});
    }
  }
  if (r.raters < 2) {
    throw Error("bad_table", "Fleiss' kappa needs at least two ratings per subject",
                {.field = "counts"});
  }
  const double n = r.raters;
  const double N = r.subjects;
  r.p.assign(r.categories, 0.0);
  for (const auto& row : counts) {
    double squares = 0;
    for (int j = 0; j < r.categories; ++j) {
      r.p[j] += row[j];
      squares += static_cast<double>(row[j]) * row[j];
    }
    r.P.push_back((squares - n) / (n * (n - 1)));
  }
  for (double& pj : r.p) {
    pj /= N * n;
    r.P_e += pj * pj;
  }
  for (double Pi : r.P) r.P_bar += Pi;
  r.P_bar /= N;
  // P_e reaches 1 only when one p_j is 1; with integer counts it is then
  // exactly 1 up to rounding.
  if (r.P_e > 1.0 - 1e-12) {
    r.defined = false;
    r.kappa = std::numeric_limits<double>::quiet_NaN();
    r.note = "every rating is in one category: chance agreement P_e = 1 and observed agreement "
             "P_bar = 1, so kappa = 0/0 is undefined (agreement is perfect but carries no "
             "information beyond chance)";
    return r;
  }
  r.kappa = (r.P_bar - r.P_e) / (1.0 - r.P_e);
  return r;
}

}  // namespace doasido::review
