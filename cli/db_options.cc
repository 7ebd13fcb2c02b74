#include "cli/commands.h"
#include "core/config_check.h"
#include "pipeline/stage_registry.h"
#include "reports/report_data.h"

namespace doasido::cli {

void AddDbOptions(CLI::App& cmd, DbOptions& options) {
  cmd.add_option("--db", options.db, "SQLite database file (created by `doasido init`)")
      ->capture_default_str();
  cmd.add_option("--config", options.config,
                 "TOML or JSON file with one table per stage (checked before any work; a bad "
                 "file exits with code 2)");
}

Json LoadConfig(const DbOptions& options) {
  if (options.config.empty()) return Json::object();
  const Json config = LoadConfigFile(options.config);
  try {
    pipeline::CheckStageConfig(config, {reports::kReportSection});
    reports::ReportOptions report;
    ReadCheckedSection(config, reports::kReportSection, report);
  } catch (const Error& e) {
    throw Error(e.code(), e.message(), {.file = options.config, .field = e.site().field});
  }
  return config;
}

}  // namespace doasido::cli
