// Bulk, read-only queries behind `doasido report` (the playbook report).
#include "db/database.h"
#include "db/clip_row.h"
#include "db/statement.h"

namespace doasido {

std::vector<Database::ReportRun> Database::ReportRuns() {
  auto& q = Prepare(
      "SELECT r.clip_id, r.stage, r.position, r.state, IFNULL(r.verdict, ''),"
      " IFNULL(r.reason, ''), IFNULL(r.error, ''), r.attempts, r.duration_s,"
      " IFNULL((SELECT v.source FROM verdicts v WHERE v.clip_id = r.clip_id"
      "         AND v.stage = r.stage ORDER BY v.id DESC LIMIT 1), ''), IFNULL(r.param_hash, ''),"
      " r.id, r.finished_at, r.inputs, IFNULL(r.requeued_by, '')"
      " FROM stage_runs r ORDER BY r.clip_id, r.position");
  std::vector<ReportRun> out;
  while (q.Step()) {
    ReportRun r;
    r.clip_id = q.Int(0);
    r.stage = q.Text(1);
    r.position = static_cast<int>(q.Int(2));
    r.state = q.Text(3);
    r.verdict = q.Text(4);
    r.reason = q.Text(5);
    r.error = q.Text(6);
    r.attempts = static_cast<int>(q.Int(7));
    if (r.state == "done") r.duration_s = q.OptReal(8);
    r.verdict_source = q.Text(9);
    r.param_hash = q.Text(10);
    r.run_id = q.Int(11);
    if (r.state == "done") {
      r.finished_at = q.OptReal(12);
      if (!q.IsNull(13)) r.inputs = Json::parse(q.Text(13), nullptr, false);
    }
    r.requeued_by = q.Text(14);
    out.push_back(std::move(r));
  }
  q.Reset();
  return out;
}

std::vector<ClipRecord> Database::ListClips(std::map<ClipId, std::string>* videos) {
  auto& q = Prepare(std::string("SELECT ") + db::kClipColumns +
                    ", COALESCE(v.local_path, v.path) FROM clips c JOIN videos v ON v.id = c.video_id ORDER BY c.id");
  std::vector<ClipRecord> out;
  while (q.Step()) {
    ClipRecord c = db::ReadClipRow(q);
    if (videos) (*videos)[c.id] = Resolve(q.Text(10)).string();
    out.push_back(std::move(c));
  }
  q.Reset();
  return out;
}

void Database::ForEachSummary(const std::string& stage,
                              const std::function<void(ClipId, const Json&)>& fn) {
  // json_extract keeps the per-frame signals out of the parser. Only runs
  // that are done count: a clip sent back by an earlier stage keeps its old
  // measurements until the stage runs again.
  auto& q = Prepare(
      "SELECT m.clip_id, CASE WHEN json_valid(m.data) THEN json_extract(m.data, '$.summary') END"
      " FROM measurements m JOIN stage_runs r ON r.clip_id = m.clip_id AND r.stage = m.stage"
      " WHERE m.stage = ? AND r.state = 'done' ORDER BY m.clip_id");
  q.Bind(1, stage);
  std::vector<std::pair<ClipId, std::string>> rows;
  while (q.Step()) rows.emplace_back(q.Int(0), q.IsNull(1) ? std::string() : q.Text(1));
  q.Reset();
  for (const auto& [clip, text] : rows) {
    Json summary = text.empty() ? Json() : Json::parse(text, nullptr, false);
    if (summary.is_discarded()) summary = Json();
    fn(clip, summary);
  }
}

std::vector<Database::EventCount> Database::CountEvents() {
  auto& q = Prepare(
      "SELECT IFNULL(stage, ''), kind, IFNULL(worker, ''), COUNT(*) FROM events"
      " GROUP BY 1, 2, 3 ORDER BY 1, 2, 3");
  std::vector<EventCount> out;
  while (q.Step()) out.push_back({q.Text(0), q.Text(1), q.Text(2), q.Int(3)});
  q.Reset();
  return out;
}

std::vector<Database::EventRow> Database::ListEvents(const std::vector<std::string>& kinds,
                                                     int limit) {
  std::string sql =
      "SELECT id, at, clip_id, IFNULL(stage, ''), kind, IFNULL(worker, ''), IFNULL(detail, '')"
      " FROM events";
  if (!kinds.empty()) {
    sql += " WHERE kind IN (";
    for (size_t i = 0; i < kinds.size(); ++i) sql += (i ? ",?" : "?");
    sql += ")";
  }
  sql += " ORDER BY id LIMIT ?";
  auto& q = Prepare(sql);
  for (size_t i = 0; i < kinds.size(); ++i) q.Bind(static_cast<int>(i + 1), kinds[i]);
  q.Bind(static_cast<int>(kinds.size() + 1), static_cast<std::int64_t>(limit > 0 ? limit : -1));
  std::vector<EventRow> out;
  while (q.Step()) {
    out.push_back({q.Int(0), q.Real(1), q.OptInt(2), q.Text(3), q.Text(4), q.Text(5),
                   q.Text(6)});
  }
  q.Reset();
  return out;
}

}  // namespace doasido
