#include "reports/html_report.h"

#include <cstdio>
#include <ctime>

#include "reports/svg_chart.h"

namespace doasido::reports {
namespace {

const char kCss[] = R"css(
body { font-family: sans-serif; margin: 24px; color: #222; max-width: 1200px; }
h1 { font-size: 22px; } h2 { font-size: 18px; margin-top: 32px; border-bottom: 1px solid #ccc; }
h3 { font-size: 15px; margin-bottom: 4px; }
table { border-collapse: collapse; margin: 8px 0; font-size: 13px; }
th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: right; vertical-align: top; }
th { background: #f0f0f0; } td.l, th.l { text-align: left; }
.reasons { font-size: 12px; color: #555; text-align: left; }
.note { background: #fff6d6; border-left: 4px solid #e0a800; padding: 4px 8px; margin: 4px 0; }
.strip { display: flex; flex-wrap: wrap; gap: 8px; }
figure { margin: 0; font-size: 11px; max-width: 520px; }
figcaption { color: #555; }
.key span { display: inline-block; width: 10px; height: 10px; margin: 0 4px 0 12px; }
.summary { font-size: 15px; }
.charts { display: flex; flex-wrap: wrap; gap: 12px; }
)css";

const char kPass[] = "#3d9a50";
const char kReject[] = "#c62828";
const char kFlag[] = "#ef8f00";
const char kFail[] = "#5d2b2b";
const char kPending[] = "#9e9e9e";
const char kNotMeasured[] = "#d7ccc8";

std::string E(const std::string& s) { return HtmlEscape(s); }
std::string N(std::int64_t v) { return std::to_string(v); }
std::string Pct(std::int64_t part, std::int64_t whole) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f%%", Percent(part, whole));
  return buf;
}
std::string Secs(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", s);
  return buf;
}

std::string ReasonList(const std::map<std::string, std::int64_t>& reasons) {
  std::string out;
  for (const auto& [reason, n] : reasons) {
    out += (out.empty() ? "" : "<br>") + E(reason) + " " + N(n);
  }
  return out;
}

std::string Key() {
  std::string s = "<div class=\"key\">";
  for (auto [colour, label] : {std::pair{kPass, "passed on"}, {kReject, "rejected"},
                               {kFlag, "flagged (review)"}, {kFail, "failed"},
                               {kPending, "pending"}, {kNotMeasured, "not measured"}}) {
    s += std::string("<span style=\"background:") + colour + "\"></span>" + label;
  }
  return s + "</div>";
}

void FunnelSection(const ReportData& d, std::string& h) {
  const auto& f = d.funnel;
  h += "<h2 id=\"funnel\">Playbook funnel</h2>";
  h += "<p class=\"summary\">Of " + N(f.pool) + " clips, " + N(f.survivors) + " (" +
       Pct(f.survivors, f.pool) + ") survive all " + N(static_cast<std::int64_t>(
                                                        d.pipeline.size())) +
       " stages.";
  for (const auto& s : f.stages) {
    if (s.rejected > 0) {
      h += " " + E(s.stage) + " removes " + N(s.rejected) + " (" + Pct(s.rejected, f.pool) +
           ").";
    }
  }
  h += "</p>";
  // Which order the rows are in: the reader compares it with the paper's.
  if (f.taken_first.empty()) {
    h += "<p id=\"funnel-order\">Stages in pipeline order: every stage measured every clip it "
         "judged.</p>";
  } else {
    std::string first;
    for (const auto& s : f.taken_first) first += (first.empty() ? "" : ", ") + E(s);
    h += "<p id=\"funnel-order\">Counted in the order the evidence was taken: " + first +
         " judged each clip before the costlier measurement of the stages after it (the hand "
         "models run only on clips the cheap verdicts keep), so a clip " + first +
         " removed is counted there, and the later stages list it as <i>not measured</i> (it "
         "moved on without being judged). With <code>learned_detector.after_cheap_verdicts = "
         "false</code> every stage measures every clip and the rows follow the pipeline.</p>";
  }
  std::vector<BarRow> rows;
  rows.push_back({"pool", {{"clips", f.pool, "#607d8b"}}, N(f.pool) + " clips"});
  for (const auto& s : f.stages) {
    rows.push_back({s.stage,
                    {{"passed on", s.passed, kPass},
                     {"flagged", s.flagged, kFlag},
                     {"rejected", s.rejected, kReject},
                     {"failed", s.failed, kFail},
                     {"pending", s.pending, kPending},
                     {"not measured", s.not_measured, kNotMeasured}},
                    N(s.entering) + " in, " + N(s.passed) + " on, −" + N(s.rejected) +
                        (s.not_measured ? ", " + N(s.not_measured) + " not measured" : "") +
                        (s.flagged ? ", " + N(s.flagged) + " flagged" : "") +
                        (s.failed ? ", " + N(s.failed) + " failed" : "")});
  }
  rows.push_back({"survivors", {{"survivors", f.survivors, kPass}},
                  N(f.survivors) + " (" + Pct(f.survivors, f.pool) + ")"});
  h += StackedBarChart(rows, f.pool, "funnel-chart", "funnel", "Playbook funnel");
  h += Key();
  h += "<table id=\"funnel-table\"><tr><th class=\"l\">stage</th><th>entering</th>"
       "<th>% of pool</th><th>rejected</th><th class=\"l\">rejected by reason</th>"
       "<th>flagged</th><th class=\"l\">flagged by reason</th><th>failed</th><th>pending</th>"
       "<th>passed on</th><th>% of pool</th><th>not measured</th><th>human verdicts</th></tr>";
  for (const auto& s : f.stages) {
    std::int64_t human = 0;
    for (const auto& [v, n] : s.human_by_verdict) human += n;
    h += "<tr data-stage=\"" + E(s.stage) + "\"><td class=\"l\">" + E(s.stage) + "</td><td>" +
         N(s.entering) + "</td><td>" + Pct(s.entering, f.pool) + "</td><td>" + N(s.rejected) +
         "</td><td class=\"reasons\">" + ReasonList(s.rejected_by_reason) + "</td><td>" +
         N(s.flagged) + "</td><td class=\"reasons\">" + ReasonList(s.flagged_by_reason) +
         "</td><td>" + N(s.failed) + "</td><td>" + N(s.pending) + "</td><td>" + N(s.passed) +
         "</td><td>" + Pct(s.passed, f.pool) + "</td><td class=\"reasons\">" +
         N(s.not_measured) + (s.not_measured ? "<br>after " + ReasonList(s.not_measured_by) : "") +
         "</td><td>" + N(human) + "</td></tr>";
  }
  h += "<tr class=\"survivors\"><td class=\"l\"><b>survivors</b></td><td colspan=\"8\"></td>"
       "<td><b>" + N(f.survivors) + "</b></td><td><b>" + Pct(f.survivors, f.pool) +
       "</b></td><td></td><td></td></tr>";
  h += "</table>";
  // The removals in the paper's words: −n per reason, with both shares.
  h += "<h3>Removed by reason</h3><table id=\"reasons-table\"><tr><th class=\"l\">stage</th>"
       "<th class=\"l\">verdict</th><th class=\"l\">reason</th><th>clips</th><th>% of pool</th>"
       "<th>% of entering</th></tr>";
  for (const auto& s : f.stages) {
    for (const auto& [verdict, reasons] :
         {std::pair{"reject", &s.rejected_by_reason}, {"flag", &s.flagged_by_reason}}) {
      for (const auto& [reason, n] : *reasons) {
        h += "<tr><td class=\"l\">" + E(s.stage) + "</td><td class=\"l\">" + verdict +
             "</td><td class=\"l\">" + E(reason) + "</td><td>" + N(n) + "</td><td>" +
             Pct(n, f.pool) + "</td><td>" + Pct(n, s.entering) + "</td></tr>";
      }
    }
  }
  h += "</table>";
}

void ScoresSection(const ReportData& d, std::string& h) {
  h += "<h2 id=\"scores\">Score distributions</h2><p>Each histogram gathers one thresholded "
       "score of a stage across clips; dashed lines are the reject (red) and flag (orange) "
       "thresholds, the shaded side rejects. Counts judge each clip by its own stored "
       "thresholds.</p>";
  for (const auto& s : d.scores) {
    h += "<h3>" + E(s.stage) + "</h3>";
    if (s.scores.empty()) {
      h += "<p class=\"note no-scores\">No thresholded scores recorded for " + E(s.stage) +
           " (" + N(s.measured) + " clips with measurements, " + N(s.with_scores) +
           " with scores).</p>";
      continue;
    }
    if (s.with_scores < s.measured) {
      h += "<p class=\"note\">" + N(s.measured - s.with_scores) + " of " + N(s.measured) +
           " measured clips have no scores for this stage.</p>";
    }
    h += "<div class=\"charts\">";
    for (const auto& dist : s.scores) {
      h += HistogramChart(dist);
      if (dist.thresholds_vary) {
        h += "<p class=\"note\">" + E(dist.name) +
             ": clips were decided with different thresholds; the most common are drawn.</p>";
      }
    }
    h += "</div>";
  }
}

void ExamplesSection(const ReportData& d, std::string& h) {
  h += "<h2 id=\"examples\">Examples per reason</h2>";
  if (d.thumbnails.empty()) {
    h += "<p>No thumbnails (none rejected, or thumbnails were turned off).</p>";
    return;
  }
  h += "<p>Boxes: hands green (L/R side, contact N none, S self, O other, P portable, F "
       "fixed), objects orange, magenta a box touching the border; a red bar between two "
       "frames is a cut; yellow arrows are camera-motion tracks.</p>";
  for (const auto& strip : d.thumbnails) {
    h += "<h3>" + E(strip.stage) + " · " + E(strip.reason) + " (" + N(strip.clips) +
         " clips, showing " + N(static_cast<std::int64_t>(strip.items.size())) + ")</h3>";
    h += "<div class=\"strip\" data-stage=\"" + E(strip.stage) + "\" data-reason=\"" +
         E(strip.reason) + "\">";
    for (const auto& t : strip.items) {
      h += "<figure>";
      if (!t.jpeg_base64.empty()) {
        h += "<img class=\"thumb\" width=\"" + N(t.width) + "\" height=\"" + N(t.height) +
             "\" alt=\"" + E(t.label + ": " + t.caption) + "\" src=\"data:image/jpeg;base64," +
             t.jpeg_base64 + "\">";
        h += "<figcaption>" + E(t.label) + " — " + E(t.caption) + "</figcaption>";
      } else {
        h += "<p class=\"note missing-video\">" + E(t.note) + "</p>";
      }
      h += "</figure>";
    }
    h += "</div>";
  }
}

void SourcesSection(const ReportData& d, std::string& h) {
  h += "<h2 id=\"sources\">By source</h2>";
  for (const auto& b : d.sources) {
    h += "<h3>" + E(b.key) + "</h3>";
    std::vector<BarRow> rows;
    std::int64_t most = 0;
    for (const auto& r : b.rows) most = std::max(most, r.clips);
    for (const auto& r : b.rows) {
      rows.push_back({r.value,
                      {{"survived", r.survived, kPass},
                       {"flagged", r.flagged, kFlag},
                       {"rejected", r.rejected, kReject},
                       {"failed", r.failed, kFail},
                       {"in progress", r.in_progress, kPending}},
                      N(r.survived) + " of " + N(r.clips) + " survive (" +
                          Pct(r.survived, r.clips) + ")"});
    }
    h += StackedBarChart(rows, most, "", "source-chart", "clips by " + b.key);
    h += "<table class=\"source-table\" data-key=\"" + E(b.key) + "\"><tr><th class=\"l\">" +
         E(b.key) + "</th><th>clips</th><th>survived</th><th>%</th><th>rejected</th>"
         "<th class=\"l\">rejected by stage:reason</th><th>flagged</th><th>failed</th>"
         "<th>in progress</th></tr>";
    for (const auto& r : b.rows) {
      h += "<tr><td class=\"l\">" + E(r.value) + "</td><td>" + N(r.clips) + "</td><td>" +
           N(r.survived) + "</td><td>" + Pct(r.survived, r.clips) + "</td><td>" +
           N(r.rejected) + "</td><td class=\"reasons\">" + ReasonList(r.rejected_by_reason) +
           "</td><td>" + N(r.flagged) + "</td><td>" + N(r.failed) + "</td><td>" +
           N(r.in_progress) + "</td></tr>";
    }
    h += "</table>";
  }
}

// The ladder of sampler presets: what each rung cost and what it saved.
void RetargetSection(const RetargetLadderStats& r, std::string& h) {
  if (r.empty()) return;
  h += "<p id=\"retarget\"><b>Retargeting</b>: " + N(r.simulated) + " clips simulated, " +
       N(r.succeeded) + " succeeded (" + Pct(r.succeeded, r.simulated) + "); " +
       N(r.not_simulated) + " done without simulation (hand-only: the kinematic trajectory "
       "kept). A clip runs the next rung only when the one before did not succeed.</p>";
  if (r.rungs.empty()) return;
  h += "<table id=\"rungs-table\"><tr><th class=\"l\">rung</th><th>clips run</th>"
       "<th>succeeded there</th><th>kept</th><th>total s</th><th>mean s</th><th>max s</th></tr>";
  for (const RungStats& s : r.rungs) {
    h += "<tr><td class=\"l\">" + E(s.rung) + "</td><td>" + N(s.ran) + "</td><td>" +
         N(s.succeeded) + "</td><td>" + N(s.kept) + "</td><td>" + Secs(s.seconds.total_s) +
         "</td><td>" + Secs(s.seconds.mean_s) + "</td><td>" + Secs(s.seconds.max_s) +
         "</td></tr>";
  }
  h += "</table>";
}

void RunsSection(const ReportData& d, std::string& h) {
  h += "<h2 id=\"runs\">Run statistics</h2><table id=\"runs-table\"><tr><th class=\"l\">stage"
       "</th><th>runs</th><th>done</th><th>failed</th><th>pending</th><th>running</th>"
       "<th>total s</th><th>mean s</th><th>median s</th><th>p95 s</th><th>max s</th>"
       "<th>attempts</th><th>retried runs</th><th>failed attempts</th>"
       "<th class=\"l\">workers (claims)</th></tr>";
  for (const auto& s : d.runs) {
    std::string workers;
    for (const auto& [w, n] : s.claims_by_worker) {
      workers += (workers.empty() ? "" : "<br>") + E(w.empty() ? "?" : w) + " " + N(n);
    }
    h += "<tr><td class=\"l\">" + E(s.stage) + "</td><td>" + N(s.runs) + "</td><td>" +
         N(s.done) + "</td><td>" + N(s.failed) + "</td><td>" + N(s.pending) + "</td><td>" +
         N(s.running) + "</td><td>" + Secs(s.duration.total_s) + "</td><td>" +
         Secs(s.duration.mean_s) + "</td><td>" + Secs(s.duration.median_s) + "</td><td>" +
         Secs(s.duration.p95_s) + "</td><td>" + Secs(s.duration.max_s) + "</td><td>" +
         N(s.attempts) + "</td><td>" + N(s.retried_runs) + "</td><td>" +
         N(s.failed_attempts) + "</td><td class=\"reasons\">" + workers + "</td></tr>";
  }
  h += "</table>";
  const DownloadStats& dl = d.downloads;
  if (dl.clips + dl.failed > 0) {
    h += "<p id=\"downloads\"><b>Downloads</b>: " + N(dl.fetched) + " fetched (" + N(dl.bytes) +
         " bytes in " + Secs(dl.seconds) + " s, " + Secs(dl.bytes_per_s / 1e6) + " MB/s), " +
         N(dl.reused) + " reused, " + N(dl.local) + " local, " + N(dl.failed) + " failed " +
         ReasonList(dl.failures_by_reason) + "</p>";
  }
  RetargetSection(d.retarget, h);
  bool any = false;
  for (const auto& s : d.runs) {
    if (s.failures.empty() && s.errors.empty()) continue;
    if (!any) h += "<h3>Failures</h3>";
    any = true;
    h += "<p><b>" + E(s.stage) + "</b>: " + N(s.failed) + " failed runs</p><ul>";
    for (const auto& [clip, error] : s.failures) {
      h += "<li>clip " + N(clip) + ": " + E(error) + "</li>";
    }
    h += "</ul>";
    if (!s.errors.empty()) {
      h += "<table class=\"errors\"><tr><th class=\"l\">error of a failed attempt</th>"
           "<th>times</th></tr>";
      int shown = 0;
      for (const auto& [error, n] : s.errors) {
        if (++shown > 10) break;
        h += "<tr><td class=\"l\">" + E(error) + "</td><td>" + N(n) + "</td></tr>";
      }
      h += "</table>";
    }
  }
}

}  // namespace

std::string RenderHtml(const ReportData& d) {
  std::string h;
  h.reserve(1 << 16);
  char when[64] = "";
  const std::time_t t = static_cast<std::time_t>(d.generated_at);
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S UTC", &tm);
  h += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
       "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
       "<title>doasido playbook report</title><style>";
  h += kCss;
  h += "</style></head><body>\n<h1>doasido playbook report</h1>";
  h += "<p>Database <code>" + E(d.database) + "</code>, generated " + when + ". Pipeline: " +
       E([&] {
         std::string p;
         for (const auto& s : d.pipeline) p += (p.empty() ? "" : " → ") + s;
         return p;
       }()) +
       ".</p>";
  h += "<p><a href=\"#funnel\">funnel</a> · <a href=\"#scores\">scores</a> · "
       "<a href=\"#examples\">examples</a> · <a href=\"#sources\">sources</a> · "
       "<a href=\"#runs\">run statistics</a> · <a href=\"#notes\">notes</a></p>\n";
  FunnelSection(d, h);
  h += "\n";
  ScoresSection(d, h);
  h += "\n";
  ExamplesSection(d, h);
  h += "\n";
  SourcesSection(d, h);
  h += "\n";
  RunsSection(d, h);
  h += "\n<h2 id=\"notes\">Notes</h2>";
  if (d.notes.empty()) h += "<p>None.</p>";
  for (const auto& n : d.notes) h += "<p class=\"note\">" + E(n) + "</p>";
  h += "<p>How counts are defined: a clip enters a stage when it was queued there (it passed "
       "the stage before); rejected clips leave the funnel, flagged ones wait for review, "
       "failed ones errored out after their attempts. Verdicts a person gave in review count as "
       "what they decided. Percentages are of the whole pool unless a column says otherwise."
       "</p>\n</body></html>\n";
  return h;
}

}  // namespace doasido::reports
