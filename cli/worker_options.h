// Worker options shared by `doasido worker` and `doasido run`.
#pragma once

#include <CLI/CLI.hpp>

#include "cli/commands.h"
#include "pipeline/worker.h"

namespace doasido::cli {

using pipeline::WorkerOptions;

void AddWorkerOptions(CLI::App& cmd, WorkerOptions& options);
// Fills in the database path, the parsed and checked config (throws
// Error("bad_config") for a bad file) and the progress bar.
WorkerOptions FinishWorkerOptions(WorkerOptions options, const DbOptions& db);

}  // namespace doasido::cli
