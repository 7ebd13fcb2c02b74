#include "reports/report_files.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"
#include "reports/source_breakdown.h"
#include "reports/svg_chart.h"

namespace doasido::reports {
namespace {

struct ValueStats {
  double min = NAN, max = NAN, mean = NAN, median = NAN;
};

ValueStats Stats(std::vector<double> v) {
  ValueStats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.min = v.front();
  s.max = v.back();
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  const size_t n = v.size();
  s.median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  return s;
}

// JSON has no NaN: missing numbers are null.
Json Num(double v) { return std::isfinite(v) ? Json(v) : Json(); }

std::string Cell(double v) {
  if (!std::isfinite(v)) return "";
  std::ostringstream out;
  out.precision(10);
  out << v;
  return out.str();
}

std::string Cell(std::int64_t v) { return std::to_string(v); }
std::string Cell(const std::string& v) { return v; }
std::string Cell(const char* v) { return v; }

// One CSV record of numbers and text (core/csv.h quotes what needs it).
template <typename... T>
std::string Row(const T&... cells) {
  return CsvLine({Cell(cells)...});
}

void Write(const std::filesystem::path& path, const std::string& text,
           std::vector<std::filesystem::path>& written) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw Error("io", "cannot write report file", {.file = path.string()});
  written.push_back(path);
}

// The parts of ReportToJson, one a section of report.json.

Json FunnelToJson(const Funnel& f) {
  Json stages = Json::array();
  for (const auto& s : f.stages) {
    stages.push_back({{"stage", s.stage},
                      {"entering", s.entering},
                      {"entering_pct", Percent(s.entering, f.pool)},
                      {"passed", s.passed},
                      {"passed_pct", Percent(s.passed, f.pool)},
                      {"rejected", s.rejected},
                      {"flagged", s.flagged},
                      {"failed", s.failed},
                      {"pending", s.pending},
                      {"not_measured", s.not_measured},
                      {"not_measured_by", s.not_measured_by},
                      {"rejected_by_reason", s.rejected_by_reason},
                      {"flagged_by_reason", s.flagged_by_reason},
                      {"passed_by_reason", s.passed_by_reason},
                      {"human_by_verdict", s.human_by_verdict}});
  }
  return {{"pool", f.pool},
          {"survivors", f.survivors},
          {"survivors_pct", Percent(f.survivors, f.pool)},
          {"without_runs", f.without_runs},
          {"stages", stages}};
}

Json ScoresToJson(const std::vector<StageScores>& all) {
  Json scores = Json::array();
  for (const auto& s : all) {
    Json list = Json::array();
    for (const auto& dist : s.scores) {
      const ValueStats v = Stats(dist.values);
      list.push_back({{"name", dist.name},
                      {"rejects", dist.rejects},
                      {"reject", Num(dist.reject)},
                      {"flag", dist.flag ? Json(*dist.flag) : Json()},
                      {"thresholds_vary", dist.thresholds_vary},
                      {"clips", dist.values.size()},
                      {"non_finite", dist.non_finite},
                      {"reject_side", dist.reject_side},
                      {"flag_zone", dist.flag_zone},
                      {"pass_side", dist.pass_side},
                      {"min", Num(v.min)},
                      {"max", Num(v.max)},
                      {"mean", Num(v.mean)},
                      {"median", Num(v.median)},
                      {"histogram", {{"lo", dist.lo}, {"hi", dist.hi}, {"bins", dist.bins}}}});
    }
    scores.push_back({{"stage", s.stage},
                      {"measured", s.measured},
                      {"with_scores", s.with_scores},
                      {"scores", list}});
  }
  return scores;
}

Json SourcesToJson(const std::vector<SourceBreakdown>& all) {
  Json sources = Json::array();
  for (const auto& b : all) {
    Json rows = Json::array();
    for (const auto& r : b.rows) {
      rows.push_back({{"value", r.value},
                      {"clips", r.clips},
                      {"survived", r.survived},
                      {"rejected", r.rejected},
                      {"flagged", r.flagged},
                      {"failed", r.failed},
                      {"in_progress", r.in_progress},
                      {"rejected_by_reason", r.rejected_by_reason}});
    }
    sources.push_back({{"key", b.key}, {"rows", rows}});
  }
  return sources;
}

Json RunsToJson(const std::vector<StageRunStats>& all) {
  Json runs = Json::array();
  for (const auto& s : all) {
    Json failures = Json::array();
    for (const auto& [clip, error] : s.failures) {
      failures.push_back({{"clip", clip}, {"error", error}});
    }
    runs.push_back({{"stage", s.stage},
                    {"runs", s.runs},
                    {"done", s.done},
                    {"failed", s.failed},
                    {"pending", s.pending},
                    {"running", s.running},
                    {"duration_s",
                     {{"count", s.duration.count},
                      {"total", s.duration.total_s},
                      {"mean", s.duration.mean_s},
                      {"median", s.duration.median_s},
                      {"p95", s.duration.p95_s},
                      {"max", s.duration.max_s}}},
                    {"attempts", s.attempts},
                    {"retried_runs", s.retried_runs},
                    {"failed_attempts", s.failed_attempts},
                    {"failures", failures},
                    {"errors", s.errors},
                    {"claims_by_worker", s.claims_by_worker}});
  }
  return runs;
}

Json ThumbnailsToJson(const std::vector<ThumbnailStrip>& all) {
  Json thumbs = Json::array();
  for (const auto& strip : all) {
    Json items = Json::array();
    for (const auto& t : strip.items) {
      items.push_back({{"clip", t.clip},
                       {"label", t.label},
                       {"caption", t.caption},
                       {"image", !t.jpeg_base64.empty()},
                       {"note", t.note}});
    }
    thumbs.push_back({{"stage", strip.stage},
                      {"verdict", strip.verdict},
                      {"reason", strip.reason},
                      {"clips", strip.clips},
                      {"items", items}});
  }
  return thumbs;
}

// funnel.csv (the pool, each stage, the survivors) and reasons.csv (each
// stage's rejects and flags by reason).
void WriteFunnelCsv(const Funnel& f, const std::filesystem::path& dir,
                    std::vector<std::filesystem::path>& written) {
  std::string funnel = "kind,stage,entering,passed,rejected,flagged,failed,pending,entering_pct,"
                       "passed_pct,not_measured\n";
  const double all = f.pool > 0 ? 100.0 : 0.0;
  funnel += Row("pool", "", f.pool, f.pool, std::int64_t{0}, std::int64_t{0}, std::int64_t{0},
                std::int64_t{0}, all, all, std::int64_t{0});
  std::string reasons = "stage,verdict,reason,clips,pct_pool,pct_entering\n";
  for (const auto& s : f.stages) {
    funnel += Row("stage", s.stage, s.entering, s.passed, s.rejected, s.flagged, s.failed,
                  s.pending, Percent(s.entering, f.pool), Percent(s.passed, f.pool),
                  s.not_measured);
    for (const auto& [reason, n] : s.rejected_by_reason) {
      reasons += Row(s.stage, "reject", reason, n, Percent(n, f.pool), Percent(n, s.entering));
    }
    for (const auto& [reason, n] : s.flagged_by_reason) {
      reasons += Row(s.stage, "flag", reason, n, Percent(n, f.pool), Percent(n, s.entering));
    }
  }
  funnel += Row("survivors", "", f.survivors, f.survivors, std::int64_t{0},
                std::int64_t{0}, std::int64_t{0}, std::int64_t{0},
                Percent(f.survivors, f.pool), Percent(f.survivors, f.pool), std::int64_t{0});
  Write(dir / "funnel.csv", funnel, written);
  Write(dir / "reasons.csv", reasons, written);
}

// scores.csv (each score's thresholds and statistics) and histograms.csv.
void WriteScoresCsv(const ReportData& d, const std::filesystem::path& dir,
                    std::vector<std::filesystem::path>& written) {
  std::string scores = "stage,score,rejects,reject,flag,clips,reject_side,flag_zone,pass_side,"
                       "non_finite,min,max,mean,median\n";
  std::string hist = "stage,score,bin,lo,hi,count\n";
  for (const auto& s : d.scores) {
    for (const auto& dist : s.scores) {
      const ValueStats v = Stats(dist.values);
      scores += Row(dist.stage, dist.name, dist.rejects, dist.reject,
                    dist.flag.value_or(NAN),
                    static_cast<std::int64_t>(dist.values.size()), dist.reject_side,
                    dist.flag_zone, dist.pass_side, dist.non_finite, v.min, v.max,
                    v.mean, v.median);
      const double n = static_cast<double>(dist.bins.size());
      for (size_t i = 0; i < dist.bins.size(); ++i) {
        hist += Row(dist.stage, dist.name, static_cast<std::int64_t>(i),
                    dist.lo + (dist.hi - dist.lo) * static_cast<double>(i) / n,
                    dist.lo + (dist.hi - dist.lo) * static_cast<double>(i + 1) / n, dist.bins[i]);
      }
    }
  }
  Write(dir / "scores.csv", scores, written);
  Write(dir / "histograms.csv", hist, written);
}

// sources.csv: outcomes by each source key's values.
void WriteSourcesCsv(const ReportData& d, const std::filesystem::path& dir,
                     std::vector<std::filesystem::path>& written) {
  std::string sources = "key,value,clips,survived,rejected,flagged,failed,in_progress\n";
  for (const auto& b : d.sources) {
    for (const auto& r : b.rows) {
      sources += Row(b.key, r.value, r.clips, r.survived, r.rejected, r.flagged, r.failed,
                     r.in_progress);
    }
  }
  Write(dir / "sources.csv", sources, written);
}

// stages.csv (run times, attempts, workers) and failures.csv (each failed
// run's error).
void WriteRunsCsv(const ReportData& d, const std::filesystem::path& dir,
                  std::vector<std::filesystem::path>& written) {
  std::string stages = "stage,runs,done,failed,pending,running,total_s,mean_s,median_s,p95_s,"
                       "max_s,attempts,retried_runs,failed_attempts,workers\n";
  std::string failures = "stage,clip,error\n";
  for (const auto& s : d.runs) {
    std::string workers;
    for (const auto& [w, n] : s.claims_by_worker) {
      workers += (workers.empty() ? "" : ";") + w + "=" + std::to_string(n);
    }
    stages += Row(s.stage, s.runs, s.done, s.failed, s.pending, s.running,
                  s.duration.total_s, s.duration.mean_s, s.duration.median_s,
                  s.duration.p95_s, s.duration.max_s, s.attempts, s.retried_runs,
                  s.failed_attempts, workers);
    for (const auto& [clip, error] : s.failures) failures += Row(s.stage, clip, error);
  }
  Write(dir / "stages.csv", stages, written);
  Write(dir / "failures.csv", failures, written);
}

// clips.csv: where each clip ended and why.
void WriteClipsCsv(const ReportData& d, const std::filesystem::path& dir,
                   std::vector<std::filesystem::path>& written) {
  std::string clips = "clip,external_id,source,outcome,stage,reason\n";
  for (const auto& c : d.clips) {
    auto it = d.outcomes.find(c.id);
    const bool known = it != d.outcomes.end();
    clips += Row(c.id, c.external_id, SourceValue(c, "source"),
                 known ? ToString(it->second.outcome) : "in_progress",
                 known ? it->second.stage : std::string(),
                 known ? it->second.reason : std::string());
  }
  Write(dir / "clips.csv", clips, written);
}

}  // namespace

Json ReportToJson(const ReportData& d) {
  return {{"database", d.database},
          {"generated_at", d.generated_at},
          {"pipeline", d.pipeline},
          {"funnel", FunnelToJson(d.funnel)},
          {"scores", ScoresToJson(d.scores)},
          {"sources", SourcesToJson(d.sources)},
          {"runs", RunsToJson(d.runs)},
          {"downloads", d.downloads.ToJson()},
          {"retarget", d.retarget.ToJson()},
          {"thumbnails", ThumbnailsToJson(d.thumbnails)},
          {"notes", d.notes}};
}

std::vector<std::filesystem::path> WriteCsvFiles(const ReportData& d,
                                                 const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> written;
  WriteFunnelCsv(d.funnel, dir, written);
  WriteScoresCsv(d, dir, written);
  WriteSourcesCsv(d, dir, written);
  WriteRunsCsv(d, dir, written);
  WriteClipsCsv(d, dir, written);
  return written;
}

}  // namespace doasido::reports
