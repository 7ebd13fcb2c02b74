#include "cli/commands.h"

namespace doasido::cli {

void AddDbOptions(CLI::App& cmd, DbOptions& options) {
  cmd.add_option("--db", options.db, "SQLite database file (created by `doasido init`)")
      ->capture_default_str();
  cmd.add_option("--config", options.config,
                 "TOML or JSON file with one table of parameters per stage");
}

Json LoadConfig(const DbOptions& options) {
  return options.config.empty() ? Json::object() : LoadConfigFile(options.config);
}

}  // namespace doasido::cli
