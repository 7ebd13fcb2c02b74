#include "reports/download_stats.h"

#include "ingest/download.h"

namespace doasido::reports {

Json DownloadStats::ToJson() const {
  return {{"clips", clips},     {"fetched", fetched},         {"reused", reused},
          {"local", local},     {"bytes", bytes},             {"seconds", seconds},
          {"bytes_per_s", bytes_per_s}, {"failed", failed},
          {"failures_by_reason", failures_by_reason}};
}

DownloadStats ComputeDownloadStats(Database& db, const std::vector<Database::ReportRun>& runs) {
  DownloadStats s;
  db.ForEachSummary(ingest::kDownloadStageName, [&s](ClipId, const Json& summary) {
    if (summary.is_null()) return;
    const ingest::DownloadSummary d = ingest::ReadDownloadSummary(summary);
    ++s.clips;
    if (d.source == "local") {
      ++s.local;
    } else if (d.source == "reused") {
      ++s.reused;
    } else {
      ++s.fetched;
      s.bytes += d.bytes;
      s.seconds += d.seconds;
    }
  });
  s.bytes_per_s = s.seconds > 0 ? static_cast<double>(s.bytes) / s.seconds : 0;
  for (const auto& r : runs) {
    if (r.stage != ingest::kDownloadStageName || r.state != "failed") continue;
    ++s.failed;
    const auto colon = r.error.find(':');
    ++s.failures_by_reason[colon == std::string::npos ? r.error : r.error.substr(0, colon)];
  }
  return s;
}

}  // namespace doasido::reports
