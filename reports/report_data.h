// Everything the playbook report shows, as plain data read from the
// database once: the funnel, score distributions, source breakdown, run
// statistics and example thumbnails. Rendering (html_report.h) and the
// machine-readable files (report_files.h) only format this.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/config.h"
#include "db/database.h"
#include "reports/download_stats.h"
#include "reports/funnel.h"
#include "reports/retarget_ladder_stats.h"
#include "reports/run_stats.h"
#include "reports/score_histogram.h"
#include "reports/source_breakdown.h"
#include "reports/thumbnails.h"

namespace doasido::reports {

// The config table `doasido report` reads its options from.
inline constexpr const char* kReportSection = "report";

struct ReportOptions {
  bool thumbnails = true;
  int histogram_bins = 20;
  int max_failures = 5;  // failed runs listed per stage
  ThumbnailOptions thumbnail;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ReportOptions, thumbnails, histogram_bins,
                                                max_failures, thumbnail)
// Valid ranges (reports/report_options.cc); throws Error("bad_config").
void CheckConfig(const ReportOptions& c, const std::string& section);

// Example clips of one (stage, verdict, reason).
struct ThumbnailStrip {
  std::string stage;
  std::string verdict;  // "reject"
  std::string reason;
  std::int64_t clips = 0;  // clips with this reason (strip shows the first few)
  std::vector<Thumbnail> items;
};

struct ReportData {
  std::string database;  // absolute path of the database file
  double generated_at = 0;  // seconds since the epoch
  std::vector<std::string> pipeline;
  Funnel funnel;
  std::vector<StageScores> scores;  // one per funnel stage, in funnel order
  std::vector<SourceBreakdown> sources;
  std::vector<StageRunStats> runs;
  DownloadStats downloads;
  RetargetLadderStats retarget;  // empty without done `retarget` runs
  std::map<ClipId, ClipOutcome> outcomes;
  std::vector<ClipRecord> clips;
  std::map<ClipId, std::string> videos;  // clip -> video path
  std::vector<ThumbnailStrip> thumbnails;
  // Things a reader must know (missing scores, unreadable videos, ...).
  std::vector<std::string> notes;
};

// Reads and computes everything but the thumbnails.
ReportData CollectReport(Database& db, const ReportOptions& options);

// Adds thumbnail strips for every rejection reason (the first
// options.thumbnail.max_per_reason clips of each, by clip id), drawing a
// progress bar. Clips whose video cannot be read get a note on the strip
// and in data.notes.
void AddThumbnails(Database& db, ReportData& data, const ReportOptions& options);

// Percentage of `part` in `whole` (0 when whole is 0).
double Percent(std::int64_t part, std::int64_t whole);

}  // namespace doasido::reports
