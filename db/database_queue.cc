// Database: the stage queue (claims, leases, results, re-queueing, counts).
#include "db/database.h"

#include <sqlite3.h>

#include <algorithm>

#include "db/statement.h"

namespace doasido {

// ---- Queue ------------------------------------------------------------------

std::optional<Claim> Database::ClaimNext(const std::string& worker,
                                         const std::vector<std::string>& stages, double lease_s,
                                         int max_attempts) {
  std::string sql =
      "SELECT id, clip_id, stage, attempts, state FROM stage_runs"
      " WHERE state IN ('pending', 'running') AND (state = 'pending' OR lease_expires < ?)"
      " AND clip_id NOT IN (SELECT clip_id FROM shard_clips)";  // shards run those
  if (!stages.empty()) {
    sql += " AND stage IN (";
    for (size_t i = 0; i < stages.size(); ++i) sql += (i ? ",?" : "?");
    sql += ")";
  }
  sql += " ORDER BY id LIMIT 1";
  Transaction tx(*this);
  const double now = Now();
  auto& find = Prepare(sql);
  for (;;) {
    find.Bind(1, now);
    for (size_t i = 0; i < stages.size(); ++i) find.Bind(static_cast<int>(i + 2), stages[i]);
    if (!find.Step()) {
      find.Reset();
      tx.Commit();
      return std::nullopt;
    }
    Claim claim{find.Int(0), find.Int(1), find.Text(2), static_cast<int>(find.Int(3)) + 1};
    const bool expired = find.Text(4) == "running";
    find.Reset();
    if (expired && claim.attempts > max_attempts) {
      const std::string error = "lease expired " + std::to_string(claim.attempts - 1) +
                                " times: the worker died or hung on this clip";
      Prepare("UPDATE stage_runs SET state = 'failed', error = ?, lease_owner = NULL,"
              " lease_expires = NULL WHERE id = ?")
          .Bind(1, error)
          .Bind(2, claim.run_id)
          .Run();
      LogEvent(claim.clip_id, claim.stage, "failed", worker, error);
      continue;
    }
    Prepare("UPDATE stage_runs SET state = 'running', attempts = ?, lease_owner = ?,"
            " lease_expires = ?, started_at = ? WHERE id = ?")
        .Bind(1, claim.attempts)
        .Bind(2, worker)
        .Bind(3, now + lease_s)
        .Bind(4, now)
        .Bind(5, claim.run_id)
        .Run();
    LogEvent(claim.clip_id, claim.stage, expired ? "reclaim" : "claim", worker,
             "attempt " + std::to_string(claim.attempts));
    tx.Commit();
    return claim;
  }
}

bool Database::Heartbeat(std::int64_t run_id, const std::string& worker, double lease_s) {
  Transaction tx(*this);
  Prepare("UPDATE stage_runs SET lease_expires = ? WHERE id = ? AND state = 'running' AND"
          " lease_owner = ?")
      .Bind(1, Now() + lease_s)
      .Bind(2, run_id)
      .Bind(3, worker)
      .Run();
  const bool held = sqlite3_changes(db_) > 0;
  tx.Commit();
  return held;
}

bool Database::Complete(const Claim& claim, const std::string& worker,
                        const std::string& param_hash, const StageResult& result,
                        double duration_s) {
  Transaction tx(*this);
  const double now = Now();
  Prepare("UPDATE stage_runs SET state = 'done', lease_owner = NULL, lease_expires = NULL,"
          " param_hash = ?, verdict = ?, reason = ?, finished_at = ?, duration_s = ?, error = NULL"
          " WHERE id = ? AND state = 'running' AND lease_owner = ?")
      .Bind(1, param_hash)
      .Bind(2, ToString(result.verdict))
      .Bind(3, result.reason)
      .Bind(4, now)
      .Bind(5, duration_s)
      .Bind(6, claim.run_id)
      .Bind(7, worker)
      .Run();
  if (sqlite3_changes(db_) == 0) return false;  // lease lost: roll back
  Prepare("INSERT OR REPLACE INTO measurements (clip_id, stage, param_hash, data, created_at)"
          " VALUES (?,?,?,?,?)")
      .Bind(1, claim.clip_id)
      .Bind(2, claim.stage)
      .Bind(3, param_hash)
      .Bind(4, result.measurements.dump())
      .Bind(5, now)
      .Run();
  Prepare("INSERT INTO verdicts (clip_id, stage, verdict, reason, source, param_hash, created_at)"
          " VALUES (?,?,?,?,'stage',?,?)")
      .Bind(1, claim.clip_id)
      .Bind(2, claim.stage)
      .Bind(3, ToString(result.verdict))
      .Bind(4, result.reason)
      .Bind(5, param_hash)
      .Bind(6, now)
      .Run();
  const auto dir = ArtifactDir(claim.clip_id, claim.stage);
  for (const auto& [kind, rel] : result.artifacts) {
    Prepare("INSERT OR IGNORE INTO artifacts (clip_id, stage, kind, path, created_at)"
            " VALUES (?,?,?,?,?)")
        .Bind(1, claim.clip_id)
        .Bind(2, claim.stage)
        .Bind(3, kind)
        .Bind(4, Store((dir / rel).string()))
        .Bind(5, now)
        .Run();
  }
  if (!result.detections.empty()) AddDetections(claim.clip_id, result.detections);
  if (result.measurements.contains(kVideoFileKey)) {
    RecordVideoFile(claim.clip_id, result.measurements.at(kVideoFileKey));
  }
  if (result.video_info) {
    const auto& v = *result.video_info;
    Prepare("UPDATE videos SET width = ?, height = ?, fps = ?, frame_count = ?, duration_s = ?,"
            " variable_frame_rate = ?, rotation_deg = ?, codec = ?, probed_at = ?"
            " WHERE id = (SELECT video_id FROM clips WHERE id = ?)")
        .Bind(1, v.width)
        .Bind(2, v.height)
        .Bind(3, v.fps)
        .Bind(4, v.frame_count)
        .Bind(5, v.duration_s)
        .Bind(6, v.variable_frame_rate ? 1 : 0)
        .Bind(7, v.rotation_deg)
        .Bind(8, v.codec)
        .Bind(9, now)
        .Bind(10, claim.clip_id)
        .Run();
  }
  MoveOn(claim.clip_id, claim.stage, result.verdict);
  LogEvent(claim.clip_id, claim.stage, "done", worker,
           std::string(ToString(result.verdict)) +
               (result.reason.empty() ? "" : " " + result.reason));
  tx.Commit();
  return true;
}

bool Database::Fail(const Claim& claim, const std::string& worker, const std::string& error,
                    int max_attempts) {
  Transaction tx(*this);
  const bool final = claim.attempts >= max_attempts;
  Prepare("UPDATE stage_runs SET state = ?, error = ?, lease_owner = NULL, lease_expires = NULL,"
          " finished_at = ? WHERE id = ? AND state = 'running' AND lease_owner = ?")
      .Bind(1, final ? "failed" : "pending")
      .Bind(2, error)
      .Bind(3, Now())
      .Bind(4, claim.run_id)
      .Bind(5, worker)
      .Run();
  const bool held = sqlite3_changes(db_) > 0;
  if (held) LogEvent(claim.clip_id, claim.stage, final ? "failed" : "retry", worker, error);
  tx.Commit();
  return held;
}

void Database::QueueNextStage(ClipId clip, const std::string& stage) {
  const int position = StagePosition(stage);
  if (position + 1 >= static_cast<int>(pipeline_cache_.size())) return;
  Prepare("INSERT OR IGNORE INTO stage_runs (clip_id, stage, position, state)"
          " VALUES (?, ?, ?, 'pending')")
      .Bind(1, clip)
      .Bind(2, pipeline_cache_[position + 1])
      .Bind(3, position + 1)
      .Run();
}

void Database::MoveOn(ClipId clip, const std::string& stage, Verdict verdict) {
  const int position = StagePosition(stage);
  const bool continues = flag_continues_cache_.count(stage) > 0;
  if (verdict == Verdict::kReject || (verdict == Verdict::kFlag && !continues)) {
    DropLaterStages(clip, stage);
    return;
  }
  if (!continues) {
    auto& flagged = Prepare("SELECT COUNT(*) FROM stage_runs WHERE clip_id = ? AND position <= ?"
                            " AND state = 'done' AND verdict = 'flag'");
    flagged.Bind(1, clip).Bind(2, position);
    const bool waits = flagged.Step() && flagged.Int(0) > 0;
    flagged.Reset();
    if (waits) return;  // the review queue lists it (ListFlagged)
  }
  QueueNextStage(clip, stage);
}

void Database::Release(ClipId clip) {
  auto& q = Prepare(
      "SELECT stage, state, IFNULL(verdict, ''),"
      " (SELECT COUNT(*) FROM stage_runs o WHERE o.clip_id = r.clip_id"
      "  AND o.verdict IN ('flag', 'reject'))"
      " FROM stage_runs r WHERE clip_id = ? ORDER BY position DESC LIMIT 1");
  q.Bind(1, clip);
  const bool found = q.Step();
  const std::string stage = found ? q.Text(0) : "", state = found ? q.Text(1) : "";
  const std::string verdict = found ? q.Text(2) : "";
  const bool held = found && q.Int(3) > 0;
  q.Reset();
  if (found && !held && state == "done" && verdict == "pass") QueueNextStage(clip, stage);
}

void Database::DropLaterStages(ClipId clip, const std::string& stage) {
  Prepare("DELETE FROM stage_runs WHERE clip_id = ? AND position > ?")
      .Bind(1, clip)
      .Bind(2, StagePosition(stage))
      .Run();
}

std::int64_t Database::InvalidateOtherParams(const std::string& stage,
                                             const std::string& param_hash) {
  Transaction tx(*this);
  // A run whose current verdict a person gave is not run again.
  Prepare("UPDATE stage_runs SET state = 'pending', attempts = 0, error = NULL"
          " WHERE stage = ? AND state = 'done' AND IFNULL(param_hash, '') != ?"
          " AND IFNULL((SELECT source FROM verdicts v WHERE v.clip_id = stage_runs.clip_id"
          " AND v.stage = stage_runs.stage ORDER BY v.id DESC LIMIT 1), '') != 'human'")
      .Bind(1, stage)
      .Bind(2, param_hash)
      .Run();
  const std::int64_t n = sqlite3_changes(db_);
  if (n > 0) {
    LogEvent(std::nullopt, stage, "params_changed", "",
             std::to_string(n) + " runs queued again for parameters " + param_hash);
  }
  tx.Commit();
  return n;
}

std::int64_t Database::Retry(const std::string& stage, std::optional<ClipId> clip) {
  Transaction tx(*this);
  Prepare("UPDATE stage_runs SET state = 'pending', attempts = 0 WHERE state = 'failed'"
          " AND (? = '' OR stage = ?) AND (? IS NULL OR clip_id = ?)")
      .Bind(1, stage)
      .Bind(2, stage)
      .Bind(3, clip)
      .Bind(4, clip)
      .Run();
  const std::int64_t n = sqlite3_changes(db_);
  LogEvent(clip, stage, "retry_failed", "", std::to_string(n) + " runs");
  tx.Commit();
  return n;
}

std::int64_t Database::Reset(const std::string& stage, std::optional<ClipId> clip) {
  const int position = StagePosition(stage);
  Transaction tx(*this);
  Prepare("DELETE FROM stage_runs WHERE position > ? AND clip_id IN (SELECT clip_id FROM"
          " stage_runs WHERE stage = ? AND (? IS NULL OR clip_id = ?))")
      .Bind(1, position)
      .Bind(2, stage)
      .Bind(3, clip)
      .Bind(4, clip)
      .Run();
  Prepare("UPDATE stage_runs SET state = 'pending', attempts = 0, error = NULL, verdict = NULL,"
          " reason = NULL, lease_owner = NULL, lease_expires = NULL, param_hash = NULL"
          " WHERE stage = ? AND (? IS NULL OR clip_id = ?)")
      .Bind(1, stage)
      .Bind(2, clip)
      .Bind(3, clip)
      .Run();
  const std::int64_t n = sqlite3_changes(db_);
  LogEvent(clip, stage, "reset", "", std::to_string(n) + " runs");
  tx.Commit();
  return n;
}

QueueSummary Database::Summary(const std::vector<std::string>& stages) {
  QueueSummary s;
  std::string sql =
      "SELECT state, COUNT(*), SUM(state = 'running' AND lease_expires < ?),"
      " SUM(clip_id IN (SELECT clip_id FROM shard_clips)) FROM stage_runs";
  for (size_t i = 0; i < stages.size(); ++i) sql += i ? ",?" : " WHERE stage IN (?";
  sql += stages.empty() ? " GROUP BY state" : ") GROUP BY state";
  auto& q = Prepare(sql);
  q.Bind(1, Now());
  for (size_t i = 0; i < stages.size(); ++i) q.Bind(static_cast<int>(i + 2), stages[i]);
  while (q.Step()) {
    const std::string state = q.Text(0);
    const std::int64_t sharded = q.Int(3);
    const std::int64_t n = q.Int(1) - (state == "pending" || state == "running" ? sharded : 0);
    if (state == "pending" || state == "running") s.sharded += sharded;
    if (state == "pending") s.pending = n;
    if (state == "running") s.running = n, s.expired = q.Int(2);
    if (state == "done") s.done = n;
    if (state == "failed") s.failed = n;
  }
  q.Reset();
  return s;
}

std::vector<StageCount> Database::Counts() {
  std::vector<StageCount> out;
  auto& q = Prepare(
      "SELECT r.stage, r.state, IFNULL(r.verdict, ''), IFNULL(r.reason, ''), COUNT(*)"
      " FROM stage_runs r LEFT JOIN pipeline p ON p.stage = r.stage"
      " GROUP BY 1, 2, 3, 4 ORDER BY IFNULL(p.position, 1e9), 2, 3, 4");
  while (q.Step()) out.push_back({q.Text(0), q.Text(1), q.Text(2), q.Text(3), q.Int(4)});
  q.Reset();
  return out;
}

std::vector<StageRunRow> Database::ListRuns(const RunFilter& f) {
  auto& q = Prepare(
      "SELECT r.id, r.clip_id, IFNULL(c.external_id, ''), r.stage, r.state, r.attempts,"
      " IFNULL(r.verdict, ''), IFNULL(r.reason, ''), IFNULL(r.error, ''),"
      " IFNULL(r.lease_owner, ''), IFNULL(r.duration_s, 0)"
      " FROM stage_runs r JOIN clips c ON c.id = r.clip_id"
      " WHERE (? = '' OR r.stage = ?) AND (? = '' OR r.state = ?) AND (? IS NULL OR r.clip_id = ?)"
      " ORDER BY r.clip_id, r.position LIMIT ?");
  q.Bind(1, f.stage)
      .Bind(2, f.stage)
      .Bind(3, f.state)
      .Bind(4, f.state)
      .Bind(5, f.clip)
      .Bind(6, f.clip)
      .Bind(7, static_cast<std::int64_t>(f.limit > 0 ? f.limit : -1));
  std::vector<StageRunRow> out;
  while (q.Step()) {
    out.push_back({q.Int(0), q.Int(1), q.Text(2), q.Text(3), ParseRunState(q.Text(4)),
                   static_cast<int>(q.Int(5)), q.Text(6), q.Text(7), q.Text(8), q.Text(9),
                   q.Real(10)});
  }
  q.Reset();
  return out;
}

std::map<std::pair<ClipId, std::string>, int> Database::DoneEventCounts() {
  std::map<std::pair<ClipId, std::string>, int> out;
  auto& q = Prepare("SELECT clip_id, stage, COUNT(*) FROM events WHERE kind = 'done'"
                    " GROUP BY 1, 2");
  while (q.Step()) out[{q.Int(0), q.Text(1)}] = static_cast<int>(q.Int(2));
  q.Reset();
  return out;
}

}  // namespace doasido
