#include "reports/source_breakdown.h"

#include <filesystem>

namespace doasido::reports {
namespace {

std::string MetadataText(const Json& metadata, const std::string& key) {
  if (!metadata.is_object() || !metadata.contains(key)) return "";
  const Json& v = metadata[key];
  if (v.is_string()) return v.get<std::string>();
  if (v.is_null()) return "";
  return v.dump();
}

}  // namespace

std::string SourceValue(const ClipRecord& clip, const std::string& key) {
  std::string value;
  if (key == "source") {
    value = MetadataText(clip.metadata, "source");
    if (value.empty()) value = MetadataText(clip.metadata, "domain");
  } else if (key == "source_list") {
    value = std::filesystem::path(clip.source_list).filename().string();
  } else {
    value = MetadataText(clip.metadata, key);
  }
  return value.empty() ? kUnknownSource : value;
}

std::vector<SourceBreakdown> ComputeSources(const std::vector<ClipRecord>& clips,
                                            const std::map<ClipId, ClipOutcome>& outcomes) {
  std::vector<SourceBreakdown> out;
  for (const std::string key : {"source", "genre", "source_list"}) {
    std::map<std::string, SourceRow> rows;
    bool any_known = false;
    for (const auto& clip : clips) {
      const std::string value = SourceValue(clip, key);
      any_known = any_known || value != kUnknownSource;
      SourceRow& row = rows[value];
      row.value = value;
      ++row.clips;
      auto it = outcomes.find(clip.id);
      const Outcome o = it == outcomes.end() ? Outcome::kInProgress : it->second.outcome;
      switch (o) {
        case Outcome::kSurvived: ++row.survived; break;
        case Outcome::kRejected:
          ++row.rejected;
          ++row.rejected_by_reason[it->second.stage + ":" + it->second.reason];
          break;
        case Outcome::kFlagged: ++row.flagged; break;
        case Outcome::kFailed: ++row.failed; break;
        case Outcome::kInProgress: ++row.in_progress; break;
      }
    }
    if (!any_known && key != "source_list") continue;
    SourceBreakdown b{.key = key};
    for (auto& [value, row] : rows) b.rows.push_back(std::move(row));
    out.push_back(std::move(b));
  }
  return out;
}

}  // namespace doasido::reports
