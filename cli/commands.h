// The command table: every `doasido <command>` is added by one function,
// defined in its own <command>_command.cc and listed in main.cc. Each
// function creates its subcommand on `app`, with a description and an
// example in the footer, and sets the callback that runs it. Callbacks
// report failure by throwing doasido::Error; main turns that into a message
// and exit code 1 (2 for a refused configuration, Error("bad_config")).
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "core/config.h"

namespace doasido {
class Database;
}

namespace doasido::cli {

// Shared options every command that touches a database takes.
struct DbOptions {
  std::string db = "doasido.db";
  std::string config;  // optional TOML/JSON file with one table per stage
};
void AddDbOptions(CLI::App& cmd, DbOptions& options);
// The parsed --config file, or an empty object. Throws Error("bad_config")
// naming the file, section.key, the value and the allowed range for a file
// that does not parse, has an unknown section or key, a value of the wrong
// type or out of range. Sections besides the stages' and the report's are
// the calling command's `other_sections` (which it checks itself).
Json LoadConfig(const DbOptions& options, const std::vector<std::string>& other_sections = {});

// The stage x state x verdict table of `doasido status`.
void PrintStatusTable(Database& db);
// One line per clip: the stage where it stopped (a reject, a failure, or
// still queued; the last stage when it went through), outcome and reason.
void PrintClipTable(Database& db);

void AddInitCommand(CLI::App& app);
void AddIngestCommand(CLI::App& app);
void AddStatusCommand(CLI::App& app);
void AddQueueCommand(CLI::App& app);
void AddWorkerCommand(CLI::App& app);
void AddRunCommand(CLI::App& app);
void AddSynthCommand(CLI::App& app);
void AddRetargetCommand(CLI::App& app);
void AddRethresholdCommand(CLI::App& app);
void AddReportCommand(CLI::App& app);
void AddReviewCommand(CLI::App& app);
void AddHandCommand(CLI::App& app);
// doasido hands: the hands stage on files (cli/hands_command.cc).
void AddHandsCommand(CLI::App& app);
// doasido objects: the objects' 2D box keypoints on files (cli/objects_command.cc).
void AddObjectsCommand(CLI::App& app);
void AddDeployCommand(CLI::App& app);
void AddDatasetCommand(CLI::App& app);
// shard, merge and slurm (cli/shard_command.cc).
void AddShardCommands(CLI::App& app);
// Per-shard progress under the status table; nothing without shards.
void PrintShardTable(Database& db);

}  // namespace doasido::cli
