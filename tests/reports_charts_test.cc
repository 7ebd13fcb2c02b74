// Score sides, histogram binning, duration statistics, escaping and the
// self-contained page, on inputs whose answers are known by hand.
#include <gtest/gtest.h>

#include <regex>

#include "reports/html_report.h"
#include "reports/report_files.h"
#include "reports/run_stats.h"
#include "reports/score_histogram.h"
#include "reports/svg_chart.h"

namespace doasido {
namespace {

using namespace doasido::reports;

TEST(ReportsCharts, ScoreSideFollowsTheFiltersComparisons) {
  // Filters reject "above" with value >= reject and flag with >= flag.
  EXPECT_EQ(ScoreSide(0.5, "above", 0.5, 0.3), "reject");
  EXPECT_EQ(ScoreSide(0.3, "above", 0.5, 0.3), "flag");
  EXPECT_EQ(ScoreSide(0.29, "above", 0.5, 0.3), "pass");
  EXPECT_EQ(ScoreSide(0.29, "above", 0.5, std::nullopt), "pass");
  // "below": the shot filter passes segment_s >= min_segment_s.
  EXPECT_EQ(ScoreSide(1.99, "below", 2.0, std::nullopt), "reject");
  EXPECT_EQ(ScoreSide(2.0, "below", 2.0, std::nullopt), "pass");
  EXPECT_EQ(ScoreSide(2.5, "below", 2.0, 3.0), "flag");
}

TEST(ReportsCharts, BinsCoverEveryValueOnce) {
  const auto bins = BinValues({0.0, 0.1, 0.25, 0.5, 0.99, 1.0, -3, 7}, 0.0, 1.0, 4);
  // [0,.25) gets 0, .1 and the clamped -3; [.25,.5) .25; [.5,.75) .5;
  // [.75,1] .99, 1.0 (top edge) and the clamped 7.
  EXPECT_EQ(bins, (std::vector<std::int64_t>{3, 1, 1, 3}));
}

TEST(ReportsCharts, CollectorCountsSidesPerClipThresholds) {
  ScoreCollector c;
  auto add = [&](double v, double reject) {
    c.Add("camera_motion", {{"scores",
                             {{{"name", "rate"}, {"value", v}, {"rejects", "above"},
                               {"reject", reject}, {"flag", 0.2}}}}});
  };
  add(0.1, 0.5);   // pass
  add(0.3, 0.5);   // flag
  add(0.6, 0.5);   // reject
  add(0.45, 0.4);  // reject by its own (re-thresholded) value
  c.Add("camera_motion", Json());          // measured, no summary
  c.Add("camera_motion", {{"scores", {{{"name", "rate"}, {"value", nullptr},
                                        {"rejects", "above"}, {"reject", 0.5}}}}});
  c.AddStage("probe");
  const auto stages = c.Finish(10);
  ASSERT_EQ(stages.size(), 2u);
  EXPECT_EQ(stages[0].measured, 6);
  EXPECT_EQ(stages[0].with_scores, 5);
  ASSERT_EQ(stages[0].scores.size(), 1u);
  const auto& d = stages[0].scores[0];
  EXPECT_EQ(d.pass_side, 1);
  EXPECT_EQ(d.flag_zone, 1);
  EXPECT_EQ(d.reject_side, 2);
  EXPECT_EQ(d.non_finite, 1);
  EXPECT_TRUE(d.thresholds_vary);
  EXPECT_DOUBLE_EQ(d.reject, 0.5);  // the most common
  std::int64_t binned = 0;
  for (auto b : d.bins) binned += b;
  EXPECT_EQ(binned, 4);
  EXPECT_LE(d.lo, 0.1);
  EXPECT_GE(d.hi, 0.6);
  EXPECT_EQ(stages[1].stage, "probe");
  EXPECT_EQ(stages[1].measured, 0);
  EXPECT_TRUE(stages[1].scores.empty());
}

TEST(ReportsCharts, DurationStatistics) {
  const auto a = ComputeDurationStats({4, 1, 3, 2});
  EXPECT_EQ(a.count, 4);
  EXPECT_DOUBLE_EQ(a.total_s, 10);
  EXPECT_DOUBLE_EQ(a.mean_s, 2.5);
  EXPECT_DOUBLE_EQ(a.median_s, 2.5);
  EXPECT_DOUBLE_EQ(a.p95_s, 4);
  EXPECT_DOUBLE_EQ(a.max_s, 4);
  // 20 values 1..20: the 95th percentile by nearest rank is the 19th.
  std::vector<double> v;
  for (int i = 20; i >= 1; --i) v.push_back(i);
  const auto b = ComputeDurationStats(v);
  EXPECT_DOUBLE_EQ(b.p95_s, 19);
  EXPECT_DOUBLE_EQ(b.median_s, 10.5);
  EXPECT_EQ(ComputeDurationStats({}).count, 0);
}

// CSV quoting is core/csv.h's (tests/core_csv_test.cc).
TEST(ReportsCharts, EscapingAndNumbers) {
  EXPECT_EQ(HtmlEscape("<a href='x'>&\"</a>"), "&lt;a href=&#39;x&#39;&gt;&amp;&quot;&lt;/a&gt;");
  EXPECT_EQ(FormatNumber(3), "3");
  EXPECT_EQ(FormatNumber(0.25), "0.25");
}

TEST(ReportsCharts, HistogramDrawsThresholdsAndCounts) {
  ScoreDistribution d;
  d.stage = "activity";
  d.name = "motion";
  d.rejects = "below";
  d.reject = 0.2;
  d.flag = 0.3;
  d.values = {0.1, 0.5};
  d.reject_side = 1;
  d.pass_side = 1;
  d.lo = 0;
  d.hi = 1;
  d.bins = BinValues(d.values, 0, 1, 10);
  const std::string svg = HistogramChart(d);
  EXPECT_EQ(svg.rfind("<svg class=\"score-chart\"", 0), 0u);
  EXPECT_NE(svg.find("threshold reject"), std::string::npos);
  EXPECT_NE(svg.find("threshold flag"), std::string::npos);
  EXPECT_NE(svg.find("reject side 1, pass side 1"), std::string::npos);
  EXPECT_EQ(std::count(svg.begin(), svg.end(), '<') , std::count(svg.begin(), svg.end(), '>'));
}

TEST(ReportsCharts, PageIsSelfContainedWithStableIds) {
  ReportData data;
  data.database = "/tmp/x <&> y.db";
  data.pipeline = {"probe", "interaction"};
  data.funnel.pool = 10;
  data.funnel.survivors = 6;
  data.funnel.stages = {{.stage = "probe", .entering = 10, .passed = 10},
                        {.stage = "interaction", .entering = 10, .passed = 6, .rejected = 4,
                         .rejected_by_reason = {{"no_interaction", 4}}}};
  data.scores = {{.stage = "probe"}};
  ThumbnailStrip strip{.stage = "interaction", .verdict = "reject", .reason = "no_interaction",
                       .clips = 4};
  strip.items.push_back({.clip = 1, .label = "c1", .caption = "x", .jpeg_base64 = "AAAA",
                         .width = 10, .height = 10});
  strip.items.push_back({.clip = 2, .label = "c2", .note = "clip c2: video file not found: /v"});
  data.thumbnails.push_back(strip);
  const std::string html = RenderHtml(data);
  EXPECT_NE(html.find("<svg id=\"funnel-chart\""), std::string::npos);
  EXPECT_NE(html.find("<table id=\"funnel-table\""), std::string::npos);
  EXPECT_NE(html.find("class=\"thumb\""), std::string::npos);
  EXPECT_NE(html.find("src=\"data:image/jpeg;base64,AAAA\""), std::string::npos);
  EXPECT_NE(html.find("clip c2: video file not found: /v"), std::string::npos);
  EXPECT_NE(html.find("/tmp/x &lt;&amp;&gt; y.db"), std::string::npos);
  EXPECT_NE(html.find("No thresholded scores recorded for probe"), std::string::npos);
  EXPECT_EQ(html.find("http"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  // Every src and href stays in the page.
  const std::regex ref("(src|href)=\"([^\"]*)\"");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), ref); it != std::sregex_iterator();
       ++it) {
    const std::string target = (*it)[2];
    EXPECT_TRUE(target.rfind("data:", 0) == 0 || target.rfind("#", 0) == 0) << target;
  }
  EXPECT_NE(html.find("survive all 2 stages"), std::string::npos);
  EXPECT_NE(html.find("60.0%"), std::string::npos);
}

}  // namespace
}  // namespace doasido
