// Fleiss' kappa (Fleiss 1971): agreement among a fixed number of raters per
// subject on nominal categories, beyond what chance would give.
//
// With N subjects, n ratings per subject and k categories, counts[i][j] is
// the number of raters who put subject i in category j (each row sums to n):
//   p_j   = sum_i counts[i][j] / (N n)            share of all ratings in j
//   P_i   = (sum_j counts[i][j]^2 - n) / (n (n - 1))   agreeing rater pairs of i
//   P_bar = mean_i P_i,   P_e = sum_j p_j^2
//   kappa = (P_bar - P_e) / (1 - P_e)
#pragma once

#include <string>
#include <vector>

namespace doasido::review {

struct FleissKappaResult {
  int subjects = 0;    // N
  int raters = 0;      // n, ratings per subject
  int categories = 0;  // k
  std::vector<double> p;  // p_j, one per category
  std::vector<double> P;  // P_i, one per subject
  double P_bar = 0;
  double P_e = 0;
  // NaN when undefined (see `defined`).
  double kappa = 0;
  // False when P_e = 1: every rating fell in one category, so chance
  // agreement is already perfect and kappa is 0/0. Observed agreement is then
  // perfect too (P_bar = 1); `note` says so.
  bool defined = true;
  std::string note;
};

// Computes Fleiss' kappa of a count table. Throws doasido::Error
// ("bad_table") when the table is empty, has rows of different lengths or
// sums, negative counts, or fewer than two ratings per subject.
FleissKappaResult FleissKappa(const std::vector<std::vector<int>>& counts);

}  // namespace doasido::review
