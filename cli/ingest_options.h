// Ingest options shared by `doasido ingest` and `doasido run`.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "db/database.h"
#include "ingest/clip_list.h"

namespace doasido::cli {

struct IngestOptions {
  std::vector<std::string> lists;
  ingest::ListOptions list;
  bool json = false;
  int max_errors_shown = 20;
};

void AddIngestOptions(CLI::App& cmd, IngestOptions& options);

// Ingests every list, printing a summary per list (bad rows named); sets the
// default pipeline on a database that has none. Returns false when a list
// could not be read at all.
bool IngestLists(Database& db, const IngestOptions& options);

}  // namespace doasido::cli
