// Download statistics of a run, like video2dataset's per-shard stats:
// how many videos were fetched or found, bytes, transfer rate, and failed
// downloads by reason.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/config.h"
#include "db/database.h"

namespace doasido::reports {

struct DownloadStats {
  std::int64_t clips = 0;       // clips with a finished download run
  std::int64_t fetched = 0;     // of those, runs that transferred the video (http or command)
  std::int64_t reused = 0;      // found the file a run for another clip had fetched
  std::int64_t local = 0;       // listed as local files: nothing to do
  std::int64_t bytes = 0;       // transferred
  double seconds = 0;           // transfer time summed over fetching runs
  double bytes_per_s = 0;       // bytes / seconds (0 without transfers)
  std::int64_t failed = 0;      // download runs in state failed
  std::map<std::string, std::int64_t> failures_by_reason;  // error code -> runs
  Json ToJson() const;
};

// From the download stage's summaries (ReadDownloadSummary) and the stage
// runs (failed runs counted by the code their error text starts with).
DownloadStats ComputeDownloadStats(Database& db, const std::vector<Database::ReportRun>& runs);

}  // namespace doasido::reports
