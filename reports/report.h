// `doasido report`: reads a database and writes the playbook report into a
// folder: report.html (self-contained), report.json and the CSV files of
// report_files.h.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "db/database.h"
#include "reports/report_data.h"

namespace doasido::reports {

struct ReportOutput {
  std::filesystem::path html;
  std::filesystem::path json;
  std::vector<std::filesystem::path> csv;
  ReportData data;
};

// Collects the report from `db`, draws thumbnails (unless turned off) and
// writes everything into `out_dir` (created). Unreadable videos become
// notes on the page; throws Error("io") naming a file it cannot write.
ReportOutput WriteReport(Database& db, const std::filesystem::path& out_dir,
                         const ReportOptions& options);

}  // namespace doasido::reports
