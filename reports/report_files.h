// The report's numbers for machines: report.json and CSV files carrying the
// same counts as the HTML page.
//   funnel.csv     kind (pool|stage|survivors), stage, entering, passed, rejected, flagged,
//                  failed, pending, entering_pct, passed_pct (of the pool)
//   reasons.csv    stage, verdict (reject|flag), reason, clips, pct_pool, pct_entering
//   scores.csv     stage, score, rejects, reject, flag, clips, reject_side, flag_zone,
//                  pass_side, non_finite, min, max, mean, median
//   histograms.csv stage, score, bin, lo, hi, count
//   sources.csv    key, value, clips, survived, rejected, flagged, failed, in_progress
//   stages.csv     run statistics: stage, runs, done, failed, pending, running, total_s,
//                  mean_s, median_s, p95_s, max_s, attempts, retried_runs, failed_attempts,
//                  workers
//   failures.csv   stage, clip, error
//   clips.csv      clip, external_id, source, outcome, stage, reason
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/config.h"
#include "reports/report_data.h"

namespace doasido::reports {

Json ReportToJson(const ReportData& data);

// Writes the CSV files above into `dir` (which must exist); returns their
// paths. Throws Error("io") naming a file it cannot write.
std::vector<std::filesystem::path> WriteCsvFiles(const ReportData& data,
                                                 const std::filesystem::path& dir);

}  // namespace doasido::reports
