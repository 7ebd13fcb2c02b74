// Worker options shared by `doasido worker` and `doasido run`.
#pragma once

#include <CLI/CLI.hpp>

#include "cli/commands.h"
#include "cli/worker.h"

namespace doasido::cli {

void AddWorkerOptions(CLI::App& cmd, WorkerOptions& options);
// Fills in the database path and parsed config.
WorkerOptions FinishWorkerOptions(WorkerOptions options, const DbOptions& db);

}  // namespace doasido::cli
