// Loading a clip list into the database: the list readers are ingest/
// (clip_list.h, which knows no database); here their rows become clips
// queued for the pipeline's first stage.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "db/database.h"
#include "ingest/clip_list.h"

namespace doasido::pipeline {

struct IngestSummary {
  std::string list;
  std::string format;
  std::int64_t rows = 0;             // good rows read from the list
  std::int64_t inserted = 0;         // new clips queued
  std::int64_t already_present = 0;  // same video and span already in the database
  std::int64_t detections = 0;
  std::vector<ingest::RowError> errors;      // refused rows, each named
  double seconds = 0;
  // Refused rows counted by the field at fault ("row" for a whole row:
  // not JSON, wrong column count, empty line).
  std::map<std::string, std::int64_t> RefusedByField() const;
  Json ToJson() const;
};

// Reads `list` and inserts its clips in batched transactions, queueing each
// new clip for the first pipeline stage. Re-ingesting the same list is a
// no-op (clips are deduplicated by video and span). Shows progress on long
// lists.
IngestSummary IngestList(Database& db, const std::filesystem::path& list,
                         const ingest::ListOptions& options = {});

}  // namespace doasido::pipeline
