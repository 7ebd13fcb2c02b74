#include "reports/svg_chart.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace doasido::reports {
namespace {

std::string Fixed(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

std::string Text(double x, double y, const std::string& text, const std::string& anchor,
                 const std::string& extra = "") {
  return "<text x=\"" + Fixed(x) + "\" y=\"" + Fixed(y) + "\" text-anchor=\"" + anchor + "\"" +
         extra + ">" + HtmlEscape(text) + "</text>";
}

}  // namespace

std::string FormatNumber(double value) {
  if (!std::isfinite(value)) return std::isnan(value) ? "NaN" : (value > 0 ? "inf" : "-inf");
  if (value == std::round(value) && std::fabs(value) < 1e9) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.0f", value);
    return buf;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", value);
  return buf;
}

std::string StackedBarChart(const std::vector<BarRow>& rows, std::int64_t scale_max,
                            const std::string& id, const std::string& css_class,
                            const std::string& title) {
  const double label_w = 170, bar_w = 420, note_w = 300, row_h = 26, top = 8;
  const double width = label_w + bar_w + note_w;
  const double height = top * 2 + row_h * static_cast<double>(rows.size());
  std::string s = "<svg";
  if (!id.empty()) s += " id=\"" + HtmlEscape(id) + "\"";
  s += " class=\"" + HtmlEscape(css_class) + "\" width=\"" + Fixed(width) + "\" height=\"" +
       Fixed(height) + "\" viewBox=\"0 0 " + Fixed(width) + " " + Fixed(height) +
       "\" role=\"img\" font-family=\"sans-serif\" font-size=\"12\">";
  s += "<title>" + HtmlEscape(title) + "</title>";
  const double scale = scale_max > 0 ? bar_w / static_cast<double>(scale_max) : 0;
  for (size_t i = 0; i < rows.size(); ++i) {
    const BarRow& row = rows[i];
    const double y = top + row_h * static_cast<double>(i);
    s += Text(label_w - 8, y + row_h * 0.65, row.label, "end");
    double x = label_w;
    s += "<rect x=\"" + Fixed(label_w) + "\" y=\"" + Fixed(y + 3) + "\" width=\"" + Fixed(bar_w) +
         "\" height=\"" + Fixed(row_h - 6) + "\" fill=\"#f2f2f2\"/>";
    for (const auto& seg : row.segments) {
      if (seg.value <= 0) continue;
      const double w = scale * static_cast<double>(seg.value);
      s += "<rect class=\"seg\" x=\"" + Fixed(x) + "\" y=\"" + Fixed(y + 3) + "\" width=\"" +
           Fixed(std::max(w, 0.5)) + "\" height=\"" + Fixed(row_h - 6) + "\" fill=\"" +
           HtmlEscape(seg.colour) + "\"><title>" +
           HtmlEscape(row.label + ": " + seg.label + " " + std::to_string(seg.value)) +
           "</title></rect>";
      x += w;
    }
    s += Text(label_w + bar_w + 8, y + row_h * 0.65, row.annotation, "start");
  }
  s += "</svg>";
  return s;
}

std::string HistogramChart(const ScoreDistribution& d) {
  const double width = 460, height = 220, left = 46, right = 12, top = 44, bottom = 40;
  const double plot_w = width - left - right, plot_h = height - top - bottom;
  std::int64_t peak = 1;
  for (auto c : d.bins) peak = std::max(peak, c);
  auto sx = [&](double v) { return left + (v - d.lo) / (d.hi - d.lo) * plot_w; };
  auto sy = [&](double c) { return top + plot_h - c / static_cast<double>(peak) * plot_h; };

  std::string s = "<svg class=\"score-chart\" data-stage=\"" +
                  HtmlEscape(d.stage) + "\" data-score=\"" + HtmlEscape(d.name) + "\" width=\"" +
                  Fixed(width) + "\" height=\"" + Fixed(height) + "\" viewBox=\"0 0 " +
                  Fixed(width) + " " + Fixed(height) +
                  "\" role=\"img\" font-family=\"sans-serif\" font-size=\"11\">";
  s += "<title>" + HtmlEscape(d.stage + " / " + d.name) + "</title>";
  s += Text(left, 14, d.stage + " · " + d.name + " (" + std::to_string(d.values.size()) +
                          " clips)", "start", " font-weight=\"bold\"");
  // The reject side, shaded.
  if (std::isfinite(d.reject)) {
    const double xr = std::clamp(sx(d.reject), left, left + plot_w);
    const double x0 = d.rejects == "below" ? left : xr;
    const double x1 = d.rejects == "below" ? xr : left + plot_w;
    s += "<rect class=\"reject-side\" x=\"" + Fixed(x0) + "\" y=\"" + Fixed(top) +
         "\" width=\"" + Fixed(std::max(0.0, x1 - x0)) + "\" height=\"" + Fixed(plot_h) +
         "\" fill=\"#fbe3e3\"/>";
  }
  const double bin_w = plot_w / static_cast<double>(std::max<size_t>(1, d.bins.size()));
  for (size_t i = 0; i < d.bins.size(); ++i) {
    if (d.bins[i] == 0) continue;
    const double lo = d.lo + (d.hi - d.lo) * static_cast<double>(i) / d.bins.size();
    const double hi = d.lo + (d.hi - d.lo) * static_cast<double>(i + 1) / d.bins.size();
    const double y = sy(static_cast<double>(d.bins[i]));
    s += "<rect class=\"bin\" x=\"" + Fixed(left + bin_w * static_cast<double>(i) + 0.5) +
         "\" y=\"" + Fixed(y) + "\" width=\"" + Fixed(std::max(bin_w - 1, 0.5)) + "\" height=\"" +
         Fixed(top + plot_h - y) + "\" fill=\"#4a78b5\"><title>" +
         HtmlEscape("[" + FormatNumber(lo) + ", " + FormatNumber(hi) + "): " +
                   std::to_string(d.bins[i]) + " clips") +
         "</title></rect>";
  }
  // Axes and ticks.
  s += "<line x1=\"" + Fixed(left) + "\" y1=\"" + Fixed(top + plot_h) + "\" x2=\"" +
       Fixed(left + plot_w) + "\" y2=\"" + Fixed(top + plot_h) + "\" stroke=\"#333\"/>";
  s += "<line x1=\"" + Fixed(left) + "\" y1=\"" + Fixed(top) + "\" x2=\"" + Fixed(left) +
       "\" y2=\"" + Fixed(top + plot_h) + "\" stroke=\"#333\"/>";
  for (int k = 0; k <= 4; ++k) {
    const double v = d.lo + (d.hi - d.lo) * k / 4.0;
    s += Text(sx(v), top + plot_h + 14, FormatNumber(v), "middle");
  }
  s += Text(left - 4, top + 8, std::to_string(peak), "end");
  s += Text(left - 4, top + plot_h, "0", "end");
  // Labels sit on two rows so that close reject and flag lines stay legible,
  // and lean inwards near the plot's ends.
  auto threshold = [&](double v, const std::string& colour, const std::string& cls,
                       const std::string& label, double label_y) {
    if (!std::isfinite(v)) return;
    const double x = std::clamp(sx(v), left, left + plot_w);
    const std::string anchor = x > left + plot_w - 50 ? "end" : x < left + 50 ? "start" : "middle";
    s += "<line class=\"" + cls + "\" x1=\"" + Fixed(x) + "\" y1=\"" + Fixed(top - 4) +
         "\" x2=\"" + Fixed(x) + "\" y2=\"" + Fixed(top + plot_h) + "\" stroke=\"" + colour +
         "\" stroke-width=\"2\" stroke-dasharray=\"5,3\"><title>" +
         HtmlEscape(label + " " + FormatNumber(v)) + "</title></line>";
    s += Text(x, label_y, label + " " + FormatNumber(v), anchor, " fill=\"" + colour + "\"");
  };
  threshold(d.reject, "#c62828", "threshold reject", "reject", top - 6);
  if (d.flag) threshold(*d.flag, "#ef8f00", "threshold flag", "flag", top - 19);
  std::string legend = "rejects " + d.rejects + ": reject side " +
                       std::to_string(d.reject_side) + ", pass side " +
                       std::to_string(d.pass_side);
  if (d.flag) legend += ", flag zone " + std::to_string(d.flag_zone);
  if (d.non_finite) legend += ", not finite " + std::to_string(d.non_finite);
  s += Text(left, height - 6, legend, "start");
  s += "</svg>";
  return s;
}

}  // namespace doasido::reports
