// Survivors and removals broken down by where clips came from: the list
// metadata's "source" (or "domain": internet / egocentric / generated),
// "genre", and the list file a clip was ingested from.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/records.h"
#include "reports/funnel.h"

namespace doasido::reports {

struct SourceRow {
  std::string value;
  std::int64_t clips = 0;
  std::int64_t survived = 0, rejected = 0, flagged = 0, failed = 0, in_progress = 0;
  std::map<std::string, std::int64_t> rejected_by_reason;  // "stage:reason" -> clips
};

struct SourceBreakdown {
  std::string key;  // "source", "genre" or "source_list"
  std::vector<SourceRow> rows;  // by value
};

inline constexpr char kUnknownSource[] = "unknown";

// The value of breakdown `key` for one clip: "source" reads metadata
// "source", else "domain"; "genre" reads metadata "genre"; "source_list"
// is the file name of the list. Missing values are kUnknownSource.
std::string SourceValue(const ClipRecord& clip, const std::string& key);

// One breakdown per key; "genre" and "source" only when at least one clip
// has the key. Clips without runs count as in progress.
std::vector<SourceBreakdown> ComputeSources(const std::vector<ClipRecord>& clips,
                                            const std::map<ClipId, ClipOutcome>& outcomes);

}  // namespace doasido::reports
