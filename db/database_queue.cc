// Database: the stage queue (claims, leases, results, re-queueing, counts).
#include "db/database.h"

#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>

#include "core/bounded_text.h"
#include "core/whole_output.h"  // ParsePid, ProcessAlive
#include "db/statement.h"

namespace doasido {
namespace {

// " AND <column> IN (?,...)" for `n` stages bound in order; "" for none.
std::string StageFilter(const char* column, size_t n) {
  if (n == 0) return "";
  std::string sql = std::string(" AND ") + column + " IN (";
  for (size_t i = 0; i < n; ++i) sql += (i ? ",?" : "?");
  return sql + ")";
}

}  // namespace

// ---- Queue ------------------------------------------------------------------

std::optional<Claim> Database::ClaimNext(const std::string& worker,
                                         const std::vector<std::string>& stages, double lease_s,
                                         int max_attempts) {
  RefuseMergedShard();
  std::string sql =
      "SELECT id, clip_id, stage, attempts, state FROM stage_runs"
      " WHERE state IN ('pending', 'running') AND (state = 'pending' OR lease_expires < ?)"
      " AND clip_id NOT IN (SELECT clip_id FROM shard_clips)"  // shards run those
      // A run waits for the earlier runs of its clip (queued again upstream).
      " AND NOT EXISTS (SELECT 1 FROM stage_runs u WHERE u.clip_id = stage_runs.clip_id"
      "  AND u.position < stage_runs.position AND u.state != 'done')";
  sql += StageFilter("stage", stages.size());
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
              " lease_expires = NULL, verdict = NULL, reason = NULL, param_hash = NULL,"
              " inputs = NULL WHERE id = ?")
          .Bind(1, error)
          .Bind(2, claim.run_id)
          .Run();
      DropLaterStages(claim.clip_id, claim.stage);
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

std::string Database::LeaseOwner(long command_pid, long worker_pid) {
  char host[256] = {0};
  gethostname(host, sizeof host - 1);
  return std::string(host) + ":" + std::to_string(command_pid) + "/" + std::to_string(worker_pid);
}

std::vector<Database::Lease> Database::ExpireDeadLeases() {
  const std::string prefix = LeaseOwner(0, 0).substr(0, LeaseOwner(0, 0).find(':') + 1);
  std::vector<Lease> dead;
  {
    auto& q = Prepare(
        "SELECT id, clip_id, stage, lease_owner, IFNULL(lease_expires, 0) FROM stage_runs"
        " WHERE state = 'running' AND substr(lease_owner, 1, length(?1)) = ?1 AND lease_expires >= ?2");
    q.Bind(1, prefix).Bind(2, Now());
    while (q.Step()) {
      const std::string owner = q.Text(3);
      const size_t slash = owner.rfind('/');
      const std::optional<long> pid =
          slash == std::string::npos ? std::nullopt : ParsePid(owner.substr(slash + 1));
      if (pid && !ProcessAlive(*pid)) {
        dead.push_back({q.Int(0), q.Int(1), q.Text(2), owner, q.Real(4)});
      }
    }
    q.Reset();
  }
  if (dead.empty()) return dead;
  Transaction tx(*this);
  for (const Lease& l : dead) {
    Prepare("UPDATE stage_runs SET lease_expires = 0 WHERE id = ? AND state = 'running'"
            " AND lease_owner = ?")
        .Bind(1, l.run_id)
        .Bind(2, l.owner)
        .Run();
  }
  tx.Commit();
  return dead;
}

std::vector<Database::Lease> Database::LiveLeases(const std::vector<std::string>& stages) {
  auto& q = Prepare(
      "SELECT id, clip_id, stage, IFNULL(lease_owner, ''), IFNULL(lease_expires, 0) FROM stage_runs"
      " WHERE state = 'running' AND lease_expires >= ?" +
      StageFilter("stage", stages.size()) + " ORDER BY id");
  q.Bind(1, Now());
  for (size_t i = 0; i < stages.size(); ++i) q.Bind(static_cast<int>(i + 2), stages[i]);
  std::vector<Lease> out;
  while (q.Step()) out.push_back({q.Int(0), q.Int(1), q.Text(2), q.Text(3), q.Real(4)});
  q.Reset();
  return out;
}

void Database::RefuseMergedShard() {
  if (const auto parent = GetMeta(kMergedIntoKey)) {
    throw Error("merged_shard",
                "this shard was merged into " + *parent +
                    "; its clips belong to that database again: run, re-queue or re-shard there",
                {.file = path_.string()});
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

// The run's measurements and its verdict (the stage's, as opposed to a person's).
void Database::RecordStageResult(const Claim& claim, const std::string& param_hash,
                                 const StageResult& result, double now) {
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
}

// Only this run's files are the stage's output now; paths relative to the
// artifact root (db/database_artifacts.cc).
void Database::ReplaceArtifactRows(const Claim& claim, const StageResult& result, double now) {
  Prepare("DELETE FROM artifacts WHERE clip_id = ? AND stage = ?")
      .Bind(1, claim.clip_id)
      .Bind(2, claim.stage)
      .Run();
  const auto dir = std::filesystem::path(std::to_string(claim.clip_id)) / claim.stage;
  for (const auto& [kind, rel] : result.artifacts) {
    Prepare("INSERT OR IGNORE INTO artifacts (clip_id, stage, kind, path, created_at)"
            " VALUES (?,?,?,?,?)")
        .Bind(1, claim.clip_id)
        .Bind(2, claim.stage)
        .Bind(3, kind)
        .Bind(4, (dir / rel).lexically_normal().generic_string())
        .Bind(5, now)
        .Run();
  }
}

// What probing found, on the clip's videos row.
void Database::RecordVideoInfo(ClipId clip, const VideoInfo& v, double now) {
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
      .Bind(10, clip)
      .Run();
}

bool Database::Complete(const Claim& claim, const std::string& worker,
                        const std::string& param_hash, const StageResult& result,
                        double duration_s) {
  Transaction tx(*this);
  const double now = Now();
  const std::string inputs = UpstreamInputs(claim.clip_id, claim.stage).dump();
  Prepare("UPDATE stage_runs SET state = 'done', lease_owner = NULL, lease_expires = NULL,"
          " param_hash = ?, verdict = ?, reason = ?, finished_at = ?, duration_s = ?, error = NULL,"
          " inputs = ?, requeued_by = NULL WHERE id = ? AND state = 'running' AND lease_owner = ?")
      .Bind(1, param_hash)
      .Bind(2, ToString(result.verdict))
      .Bind(3, result.reason)
      .Bind(4, now)
      .Bind(5, duration_s)
      .Bind(6, inputs)
      .Bind(7, claim.run_id)
      .Bind(8, worker)
      .Run();
  if (sqlite3_changes(db_) == 0) return false;  // lease lost: roll back
  RecordStageResult(claim, param_hash, result, now);
  ReplaceArtifactRows(claim, result, now);
  if (!result.detections.empty()) AddDetections(claim.clip_id, result.detections);
  if (result.measurements.contains(kVideoFileKey)) {
    RecordVideoFile(claim.clip_id, result.measurements.at(kVideoFileKey));
  }
  if (result.video_info) RecordVideoInfo(claim.clip_id, *result.video_info, now);
  // Later runs consumed the previous result of this stage (there are none
  // on a clip's first pass): they run again after it.
  const std::int64_t requeued = RequeueDownstream(claim.clip_id, claim.stage);
  if (requeued > 0) {
    LogEvent(claim.clip_id, claim.stage, "requeue_downstream", worker,
             std::to_string(requeued) + " later runs queued again");
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
  const std::string stored = BoundedTail(error);
  // A failed attempt has no verdict: the one of an earlier run (other
  // parameters, other upstream results) does not describe it.
  Prepare("UPDATE stage_runs SET state = ?, error = ?, lease_owner = NULL, lease_expires = NULL,"
          " finished_at = ?, verdict = NULL, reason = NULL, param_hash = NULL, inputs = NULL"
          " WHERE id = ? AND state = 'running' AND lease_owner = ?")
      .Bind(1, final ? "failed" : "pending")
      .Bind(2, stored)
      .Bind(3, Now())
      .Bind(4, claim.run_id)
      .Bind(5, worker)
      .Run();
  const bool held = sqlite3_changes(db_) > 0;
  // Runs after a failed one would wait for it forever.
  if (held && final) DropLaterStages(claim.clip_id, claim.stage);
  if (held) LogEvent(claim.clip_id, claim.stage, final ? "failed" : "retry", worker, stored);
  if (held) DiscardArtifacts(claim.clip_id, {claim.stage});  // no earlier run's output stays
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
    if (waits) {  // the review queue lists it (ListFlagged); Release goes on
      DropLaterStages(clip, stage);
      return;
    }
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
  const bool moves_on = verdict == ToString(Verdict::kPass) ||
                        verdict == ToString(Verdict::kNotMeasured);
  if (found && !held && state == "done" && moves_on) QueueNextStage(clip, stage);
}

void Database::DropLaterStages(ClipId clip, const std::string& stage) {
  DiscardArtifacts(clip, StagesAfter(stage));
  Prepare("DELETE FROM stage_runs WHERE clip_id = ? AND position > ?")
      .Bind(1, clip)
      .Bind(2, StagePosition(stage))
      .Run();
}

std::int64_t Database::InvalidateOtherParams(const std::string& stage,
                                             const std::string& param_hash,
                                             std::int64_t* downstream) {
  Transaction tx(*this);
  // A run whose current verdict a person gave is not run again.
  const char* const kChanged =
      " WHERE stage = ? AND state = 'done' AND IFNULL(param_hash, '') != ?"
      " AND IFNULL((SELECT source FROM verdicts v WHERE v.clip_id = stage_runs.clip_id"
      " AND v.stage = stage_runs.stage ORDER BY v.id DESC LIMIT 1), '') != 'human'";
  auto& find = Prepare(std::string("SELECT clip_id FROM stage_runs") + kChanged);
  find.Bind(1, stage).Bind(2, param_hash);
  std::vector<ClipId> clips;
  while (find.Step()) clips.push_back(find.Int(0));
  find.Reset();
  Prepare(std::string("UPDATE stage_runs SET state = 'pending', attempts = 0, error = NULL,"
                      " verdict = NULL, reason = NULL") + kChanged)
      .Bind(1, stage)
      .Bind(2, param_hash)
      .Run();
  const std::int64_t n = sqlite3_changes(db_);
  std::int64_t later = 0;
  for (const ClipId clip : clips) {
    DiscardArtifacts(clip, {stage});  // its old output is no longer any run's recorded result
    later += RequeueDownstream(clip, stage);
  }
  if (downstream) *downstream = later;
  if (n > 0) {
    LogEvent(std::nullopt, stage, "params_changed", "",
             std::to_string(n) + " runs queued again for parameters " + param_hash + ", " +
                 std::to_string(later) + " later runs with them");
  }
  tx.Commit();
  return n;
}

std::int64_t Database::RequeueDownstream(ClipId clip, const std::string& stage) {
  Prepare("UPDATE stage_runs SET state = 'pending', attempts = 0, error = NULL, verdict = NULL,"
          " reason = NULL, lease_owner = NULL, lease_expires = NULL, requeued_by = ?"
          " WHERE clip_id = ? AND position > ?"
          " AND NOT (state = 'pending' AND IFNULL(requeued_by, '') = ?)")
      .Bind(1, stage)
      .Bind(2, clip)
      .Bind(3, StagePosition(stage))
      .Bind(4, stage)
      .Run();
  const std::int64_t n = sqlite3_changes(db_);
  // Their old outputs came from the previous upstream result.
  if (n > 0) DiscardArtifacts(clip, StagesAfter(stage));
  return n;
}

Json Database::UpstreamInputs(ClipId clip, const std::string& stage) {
  auto& q = Prepare(
      "SELECT r.stage, IFNULL(r.param_hash, ''), r.finished_at,"
      " (SELECT json_group_array(a.path) FROM artifacts a WHERE a.clip_id = r.clip_id"
      "  AND a.stage = r.stage)"
      " FROM stage_runs r WHERE r.clip_id = ? AND r.position < ? AND r.state = 'done'"
      " ORDER BY r.position");
  q.Bind(1, clip).Bind(2, StagePosition(stage));
  Json out = Json::array();
  while (q.Step()) {
    out.push_back({{"stage", q.Text(0)},
                   {"param_hash", q.Text(1)},
                   {"finished_at", q.OptReal(2).value_or(0)},
                   {"artifacts", Json::parse(q.Text(3), nullptr, false)}});
  }
  q.Reset();
  return out;
}

std::int64_t Database::CountOpen(const std::vector<std::string>& stages) {
  std::string sql =
      "SELECT COUNT(*) FROM stage_runs r WHERE (r.state = 'running' OR (r.state = 'pending'"
      " AND NOT EXISTS (SELECT 1 FROM stage_runs u WHERE u.clip_id = r.clip_id"
      "  AND u.position < r.position AND u.state != 'done')))"
      " AND r.clip_id NOT IN (SELECT clip_id FROM shard_clips)";
  sql += StageFilter("r.stage", stages.size());
  auto& q = Prepare(sql);
  for (size_t i = 0; i < stages.size(); ++i) q.Bind(static_cast<int>(i + 1), stages[i]);
  const std::int64_t n = q.Step() ? q.Int(0) : 0;
  q.Reset();
  return n;
}

std::map<std::string, std::int64_t> Database::CountRequeued() {
  std::map<std::string, std::int64_t> out;
  auto& q = Prepare("SELECT requeued_by, COUNT(*) FROM stage_runs WHERE state IN ('pending',"
                    " 'running') AND requeued_by IS NOT NULL GROUP BY 1");
  while (q.Step()) out[q.Text(0)] = q.Int(1);
  q.Reset();
  return out;
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
  {
    std::vector<std::string> stages = StagesAfter(stage);
    stages.insert(stages.begin(), stage);
    std::vector<ClipId> clips;
    auto& find = Prepare("SELECT clip_id FROM stage_runs WHERE stage = ? AND (? IS NULL OR clip_id = ?)");
    find.Bind(1, stage).Bind(2, clip).Bind(3, clip);
    while (find.Step()) clips.push_back(find.Int(0));
    find.Reset();
    for (ClipId c : clips) DiscardArtifacts(c, stages);
  }
  Prepare("DELETE FROM stage_runs WHERE position > ? AND clip_id IN (SELECT clip_id FROM"
          " stage_runs WHERE stage = ? AND (? IS NULL OR clip_id = ?))")
      .Bind(1, position)
      .Bind(2, stage)
      .Bind(3, clip)
      .Bind(4, clip)
      .Run();
  Prepare("UPDATE stage_runs SET state = 'pending', attempts = 0, error = NULL, verdict = NULL,"
          " reason = NULL, lease_owner = NULL, lease_expires = NULL, param_hash = NULL,"
          " inputs = NULL, requeued_by = NULL WHERE stage = ? AND (? IS NULL OR clip_id = ?)")
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
