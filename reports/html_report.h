// The report as one self-contained HTML page: inline CSS, inline SVG charts,
// thumbnails as data: URIs; no scripts and no network.
//
// Stable hooks for browser tests: the funnel chart is <svg id="funnel-chart">,
// the funnel table <table id="funnel-table">, each score histogram an
// <svg class="score-chart">, each thumbnail an <img class="thumb">.
#pragma once

#include <string>

#include "reports/report_data.h"

namespace doasido::reports {

std::string RenderHtml(const ReportData& data);

}  // namespace doasido::reports
