// Reading a doasido database as plain rows, for tests that compare two
// databases table by table (shards, merges). Header-only: only tests that
// link SQLite (through doasido::db) include it.
#pragma once

#include <sqlite3.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace doasido::testing {

// Every row of `sql` on the file at `db`, its cells joined by '|' (NULL as
// "~"). Opened read-only; throws std::runtime_error on SQL errors.
inline std::vector<std::string> QueryRows(const std::filesystem::path& db, const std::string& sql) {
  sqlite3* raw = nullptr;
  if (sqlite3_open_v2(db.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    sqlite3_close(raw);
    throw std::runtime_error("cannot open " + db.string());
  }
  // A worker may be creating or writing the file right now.
  sqlite3_busy_timeout(raw, 10000);
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(raw, sql.c_str(), -1, &stmt, nullptr) != SQLITE_OK) {
    const std::string message = sqlite3_errmsg(raw);
    sqlite3_close(raw);
    throw std::runtime_error(message + ": " + sql);
  }
  std::vector<std::string> rows;
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    std::string row;
    for (int c = 0; c < sqlite3_column_count(stmt); ++c) {
      const auto* text = sqlite3_column_text(stmt, c);
      row += (c ? "|" : "") + (text ? std::string(reinterpret_cast<const char*>(text)) : "~");
    }
    rows.push_back(row);
  }
  sqlite3_finalize(stmt);
  sqlite3_close(raw);
  return rows;
}

// What a clip's processing produced, without row ids, times, workers and
// attempts (which differ between machines that did the same work): per
// table, rows ordered canonically.
inline std::vector<std::vector<std::string>> ResultTables(const std::filesystem::path& db) {
  return {
      QueryRows(db, "SELECT clip_id, stage, position, state, param_hash, verdict, reason, error"
                    " FROM stage_runs ORDER BY clip_id, position"),
      QueryRows(db, "SELECT clip_id, stage, param_hash, data FROM measurements"
                    " ORDER BY clip_id, stage"),
      QueryRows(db, "SELECT clip_id, stage, verdict, reason, source, param_hash FROM verdicts"
                    " ORDER BY clip_id, stage, id"),
      QueryRows(db, "SELECT clip_id, stage, kind, path FROM artifacts ORDER BY 1, 2, 3, 4"),
      QueryRows(db, "SELECT clip_id, frame, kind, x1, y1, x2, y2, score, contact_state, source"
                    " FROM detections ORDER BY 1, 2, 3, 4, 5"),
      QueryRows(db, "SELECT c.id, c.external_id, c.start_frame, c.end_frame, v.frame_count"
                    " FROM clips c JOIN videos v ON v.id = c.video_id ORDER BY c.id"),
  };
}

}  // namespace doasido::testing
