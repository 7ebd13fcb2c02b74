// Fleiss' kappa against the published worked example and its defining
// properties.
#include "review/fleiss_kappa.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace doasido::review {
namespace {

// Fleiss (1971) as worked on Wikipedia's "Fleiss' kappa" page: 10 subjects,
// 14 raters each, 5 categories.
const std::vector<std::vector<int>> kWorkedExample = {
    {0, 0, 0, 0, 14}, {0, 2, 6, 4, 2}, {0, 0, 3, 5, 6}, {0, 3, 9, 2, 0}, {2, 2, 8, 1, 1},
    {7, 7, 0, 0, 0},  {3, 2, 6, 3, 0}, {2, 5, 3, 2, 2}, {6, 5, 2, 1, 0}, {0, 2, 2, 3, 7}};

TEST(FleissKappa, MatchesThePublishedWorkedExample) {
  const auto r = FleissKappa(kWorkedExample);
  EXPECT_EQ(r.subjects, 10);
  EXPECT_EQ(r.raters, 14);
  EXPECT_EQ(r.categories, 5);
  ASSERT_TRUE(r.defined);
  // Published, rounded to three decimals.
  EXPECT_NEAR(r.P_bar, 0.378, 5e-4);
  EXPECT_NEAR(r.P_e, 0.213, 5e-4);
  EXPECT_NEAR(r.kappa, 0.210, 5e-4);
  const std::vector<double> p = {0.143, 0.200, 0.279, 0.150, 0.229};
  ASSERT_EQ(r.p.size(), p.size());
  for (size_t j = 0; j < p.size(); ++j) EXPECT_NEAR(r.p[j], p[j], 5e-4) << j;
  const std::vector<double> P = {1.000, 0.253, 0.308, 0.440, 0.330,
                                 0.462, 0.242, 0.176, 0.286, 0.286};
  ASSERT_EQ(r.P.size(), P.size());
  for (size_t i = 0; i < P.size(); ++i) EXPECT_NEAR(r.P[i], P[i], 5e-4) << i;
}

TEST(FleissKappa, PerfectAgreementIsOne) {
  const auto r = FleissKappa({{3, 0, 0}, {0, 3, 0}, {0, 0, 3}, {3, 0, 0}});
  ASSERT_TRUE(r.defined);
  EXPECT_DOUBLE_EQ(r.P_bar, 1.0);
  EXPECT_NEAR(r.kappa, 1.0, 1e-12);
}

TEST(FleissKappa, SplitPairsGiveMinusOne) {
  // Two raters who always disagree over two equally used categories:
  // P_bar = 0, P_e = 1/2, kappa = -1.
  const auto r = FleissKappa({{1, 1}, {1, 1}, {1, 1}});
  ASSERT_TRUE(r.defined);
  EXPECT_DOUBLE_EQ(r.P_bar, 0.0);
  EXPECT_DOUBLE_EQ(r.P_e, 0.5);
  EXPECT_NEAR(r.kappa, -1.0, 1e-12);
}

TEST(FleissKappa, AgreementAtChanceLevelIsZero) {
  // Each category pair of subjects mirrors the other, so observed agreement
  // equals the agreement expected from the pooled shares.
  const auto r = FleissKappa({{2, 0}, {0, 2}, {1, 1}, {1, 1}});
  // P_i = 1, 1, 0, 0 -> P_bar 0.5; p = (0.5, 0.5) -> P_e 0.5.
  EXPECT_DOUBLE_EQ(r.P_bar, 0.5);
  EXPECT_DOUBLE_EQ(r.P_e, 0.5);
  EXPECT_NEAR(r.kappa, 0.0, 1e-12);
}

TEST(FleissKappa, AllRatingsInOneCategoryIsUndefinedNotANumber) {
  const auto r = FleissKappa({{0, 3, 0}, {0, 3, 0}});
  EXPECT_FALSE(r.defined);
  EXPECT_TRUE(std::isnan(r.kappa));
  EXPECT_DOUBLE_EQ(r.P_bar, 1.0);
  EXPECT_DOUBLE_EQ(r.P_e, 1.0);
  EXPECT_NE(r.note.find("P_e = 1"), std::string::npos);
}

TEST(FleissKappa, InvariantToOrderOfSubjectsAndCategories) {
  auto shuffled = kWorkedExample;
  std::reverse(shuffled.begin(), shuffled.end());
  for (auto& row : shuffled) std::rotate(row.begin(), row.begin() + 2, row.end());
  EXPECT_NEAR(FleissKappa(shuffled).kappa, FleissKappa(kWorkedExample).kappa, 1e-12);
}

TEST(FleissKappa, RejectsMalformedTables) {
  EXPECT_THROW(FleissKappa({}), Error);
  EXPECT_THROW(FleissKappa({{1, 2}, {2, 2}}), Error);     // different rater counts
  EXPECT_THROW(FleissKappa({{1, 2}, {3}}), Error);        // ragged
  EXPECT_THROW(FleissKappa({{1, 0}, {0, 1}}), Error);     // one rater per subject
  EXPECT_THROW(FleissKappa({{3, -1}, {1, 1}}), Error);    // negative
}

}  // namespace
}  // namespace doasido::review
