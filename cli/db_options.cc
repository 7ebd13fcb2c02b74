#include <filesystem>

#include "cli/commands.h"
#include "core/config_check.h"
#include "stages/stage_registry.h"
#include "reports/report_data.h"

namespace doasido::cli {

void AddDbOptions(CLI::App& cmd, DbOptions& options) {
  cmd.add_option("--db", options.db, "SQLite database file (created by `doasido init`)")
      ->capture_default_str();
  cmd.add_option("--config", options.config,
                 "TOML or JSON file with one table per stage (checked before any work; a bad "
                 "file exits with code 2)")
      ->each([](const std::string& path) {
        // Every command that takes --config refuses a missing file, also
        // the ones that read no section of it.
        std::error_code ec;
        const auto status = std::filesystem::status(path, ec);
        if (!std::filesystem::is_regular_file(status)) {
          throw Error("bad_config",
                      std::filesystem::exists(status) ? "the config is not a regular file"
                                                      : "no such config file",
                      {.file = path});
        }
      });
}

Json LoadConfig(const DbOptions& options, const std::vector<std::string>& other_sections) {
  if (options.config.empty()) return Json::object();
  const Json config = LoadConfigFile(options.config);
  try {
    std::vector<std::string> sections = other_sections;
    sections.push_back(reports::kReportSection);
    stages::CheckStageConfig(config, sections);
    reports::ReportOptions report;
    ReadCheckedSection(config, reports::kReportSection, report);
  } catch (const Error& e) {
    throw Error(e.code(), e.message(), {.file = options.config, .field = e.site().field});
  }
  return config;
}

}  // namespace doasido::cli
