#include "pipeline/ingest.h"

#include <chrono>

#include "core/progress.h"

namespace doasido::pipeline {

std::map<std::string, std::int64_t> IngestSummary::RefusedByField() const {
  std::map<std::string, std::int64_t> counts;
  for (const auto& e : errors) ++counts[e.field.empty() ? "row" : e.field];
  return counts;
}

Json IngestSummary::ToJson() const {
  Json bad = Json::array();
  for (const auto& e : errors) {
    bad.push_back({{"file", e.file}, {"line", e.line}, {"field", e.field}, {"reason", e.reason}});
  }
  return {{"list", list},
          {"format", format},
          {"rows", rows},
          {"inserted", inserted},
          {"already_present", already_present},
          {"detections", detections},
          {"bad_rows", errors.size()},
          {"bad_rows_by_field", RefusedByField()},
          {"errors", bad},
          {"seconds", seconds}};
}

IngestSummary IngestList(Database& db, const std::filesystem::path& list,
                         const ingest::ListOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  ingest::ListReadResult read = ingest::ReadClipList(list, options);
  IngestSummary summary;
  summary.list = list.string();
  summary.format = read.format;
  summary.rows = static_cast<std::int64_t>(read.rows.size());
  summary.errors = std::move(read.errors);

  constexpr size_t kBatch = 20000;
  Progress progress("ingest", read.rows.size());
  std::unordered_map<std::string, VideoId> videos;
  for (size_t begin = 0; begin < read.rows.size(); begin += kBatch) {
    const size_t end = std::min(read.rows.size(), begin + kBatch);
    const std::int64_t committed = summary.inserted;
    try {
      Database::Transaction tx(db);
      for (size_t i = begin; i < end; ++i) {
        ingest::ListRow& row = read.rows[i];
        auto [it, fresh] = videos.emplace(row.video, 0);
        if (fresh) it->second = db.UpsertVideo(row.video);
        row.clip.video_id = it->second;
        const auto result = db.InsertClip(row.clip);
        if (result.inserted) {
          ++summary.inserted;
          if (!row.detections.empty()) {
            db.AddDetections(result.id, row.detections);
            summary.detections += static_cast<std::int64_t>(row.detections.size());
          }
        } else {
          ++summary.already_present;
        }
      }
      if (end == read.rows.size()) {
        db.LogEvent(std::nullopt, "", "ingest", "",
                    list.string() + ": " + std::to_string(summary.inserted) + " new clips, " +
                        std::to_string(summary.errors.size()) + " bad rows");
      }
      tx.Commit();
    } catch (const Error& e) {
      // Earlier batches are committed; this one was rolled back whole.
      throw Error(e.code(),
                  e.message() + " while ingesting " + list.string() + " (rows " +
                      std::to_string(begin + 1) + "-" + std::to_string(end) + " rolled back; " +
                      std::to_string(committed) + " clips of this list were recorded before)",
                  e.site());
    }
    progress.Set(end);
  }
  progress.Finish();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace doasido::pipeline
