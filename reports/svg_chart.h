// Inline SVG charts for the report, drawn as text: no scripts, no external
// resources, so the page opens from disk in any browser.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/html_escape.h"
#include "reports/score_histogram.h"

namespace doasido::reports {

// A short, locale-independent number: integers as such, else 3 significant
// digits ("0.25", "1.2e+03").
std::string FormatNumber(double value);

struct BarSegment {
  std::string label;  // shown in the tooltip
  std::int64_t value = 0;
  std::string colour;  // CSS colour
};

struct BarRow {
  std::string label;  // left of the bar
  std::vector<BarSegment> segments;
  std::string annotation;  // right of the bar
};

// Horizontal stacked bars, one row each; a bar's length is the sum of its
// segments relative to `scale_max`. The <svg> gets `id` (if not empty)
// and `css_class`.
std::string StackedBarChart(const std::vector<BarRow>& rows, std::int64_t scale_max,
                            const std::string& id, const std::string& css_class,
                            const std::string& title);

// A histogram of one score with its reject (red) and flag (orange)
// thresholds drawn and the reject side shaded; counts each side in the
// legend. The <svg> has class "score-chart" and data-stage/data-score.
std::string HistogramChart(const ScoreDistribution& dist);

}  // namespace doasido::reports
