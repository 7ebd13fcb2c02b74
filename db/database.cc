#include "db/database.h"

#include <sqlite3.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "db/clip_row.h"
#include "db/schema.h"
#include "db/statement.h"

namespace doasido {
namespace {

bool IsUrl(const std::string& s) { return s.find("://") != std::string::npos; }

struct BusyState {
  double timeout_s;
  std::chrono::steady_clock::time_point start;
};

// SQLite's default busy handler sleeps in steps of milliseconds, which caps
// a contended queue at a few hundred claims per second. Short, growing
// sleeps keep short transactions flowing between processes.
int BusyHandler(void* arg, int count) {
  auto* state = static_cast<BusyState*>(arg);
  const auto now = std::chrono::steady_clock::now();
  if (count == 0) state->start = now;
  if (std::chrono::duration<double>(now - state->start).count() > state->timeout_s) return 0;
  const int micros = std::min(2000, 10 << std::min(count, 8));
  std::this_thread::sleep_for(std::chrono::microseconds(micros));
  return 1;
}

}  // namespace

double Now() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<double>(ts.tv_sec) + ts.tv_nsec * 1e-9;
}

const char* ToString(RunState s) {
  switch (s) {
    case RunState::kPending: return "pending";
    case RunState::kRunning: return "running";
    case RunState::kDone: return "done";
    case RunState::kFailed: return "failed";
  }
  return "?";
}

Database::Database(const std::filesystem::path& path, double busy_timeout_s)
    : busy_timeout_s_(busy_timeout_s) {
  path_ = std::filesystem::absolute(path).lexically_normal();
  root_ = path_.parent_path();
  if (!std::filesystem::exists(root_)) {
    throw Error("database", "folder does not exist", {.file = path_.string()});
  }
  if (sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                      nullptr) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw Error("database", "cannot open: " + message, {.file = path_.string()});
  }
  static thread_local BusyState busy_state;
  busy_state.timeout_s = busy_timeout_s_;
  sqlite3_busy_handler(db_, BusyHandler, &busy_state);
  try {
    // WAL lets readers and one writer work at once; NORMAL sync is durable
    // against process crashes (a killed worker), which is what the queue
    // must survive. Reads go through mmap to spare a copy per page.
    db::Exec(db_, "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON;"
                  " PRAGMA mmap_size=268435456; PRAGMA cache_size=-65536;");
    Migrate();
  } catch (const Error& e) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw Error(e.code(), e.message(), {.file = path_.string()});
  }
}

Database::~Database() {
  statements_.clear();
  if (db_) sqlite3_close(db_);
}

db::Statement& Database::Prepare(const std::string& sql) {
  auto& slot = statements_[sql];
  if (!slot) slot = std::make_unique<db::Statement>(db_, sql);
  return *slot;
}

int Database::LatestSchemaVersion() { return static_cast<int>(db::Migrations().size()); }

int Database::SchemaVersion() {
  return static_cast<int>(QueryInt("SELECT version FROM schema_version"));
}

void Database::Migrate() {
  db::Exec(db_, "CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL)");
  Transaction tx(*this);
  int version = SchemaVersion();
  if (version == 0 && QueryInt("SELECT COUNT(*) FROM schema_version") == 0) {
    Prepare("INSERT INTO schema_version VALUES (0)").Run();
  }
  const auto& migrations = db::Migrations();
  if (version > static_cast<int>(migrations.size())) {
    throw Error("database", "schema version " + std::to_string(version) +
                                " is newer than this doasido (" +
                                std::to_string(migrations.size()) + "): upgrade doasido");
  }
  for (; version < static_cast<int>(migrations.size()); ++version) {
    db::Exec(db_, migrations[version]);
    Prepare("UPDATE schema_version SET version = ?").Bind(1, version + 1).Run();
  }
  tx.Commit();
}

// ---- Paths ------------------------------------------------------------------

std::filesystem::path Database::ArtifactDir(ClipId clip, const std::string& stage) const {
  return root_ / "artifacts" / std::to_string(clip) / stage;
}

std::filesystem::path Database::Resolve(const std::string& stored) const {
  if (IsUrl(stored)) return stored;
  const std::filesystem::path p(stored);
  return p.is_absolute() ? p : (root_ / p).lexically_normal();
}

std::string Database::Store(const std::string& path_or_url) const {
  if (IsUrl(path_or_url)) return path_or_url;
  const auto abs = std::filesystem::absolute(path_or_url).lexically_normal();
  const auto rel = abs.lexically_relative(root_);
  // Inside the database folder: relative, so the folder moves as a whole.
  if (!rel.empty() && *rel.begin() != "..") return rel.string();
  return abs.string();
}

// ---- Transactions -----------------------------------------------------------

Database::Transaction::Transaction(Database& db) : db_(db), nested_(db.transaction_depth_ > 0) {
  db::Exec(db_.db_, nested_ ? "SAVEPOINT nested" : "BEGIN IMMEDIATE");
  ++db_.transaction_depth_;
}

Database::Transaction::~Transaction() {
  if (done_) return;
  --db_.transaction_depth_;
  sqlite3_exec(db_.db_, nested_ ? "ROLLBACK TO nested; RELEASE nested" : "ROLLBACK", nullptr,
               nullptr, nullptr);
}

void Database::Transaction::Commit() {
  db::Exec(db_.db_, nested_ ? "RELEASE nested" : "COMMIT");
  --db_.transaction_depth_;
  done_ = true;
}

// ---- Pipeline ---------------------------------------------------------------

void Database::SetPipeline(const std::vector<std::string>& stages) {
  Transaction tx(*this);
  const auto current = Pipeline();
  if (QueryInt("SELECT COUNT(*) FROM stage_runs") > 0) {
    const bool appends = stages.size() >= current.size() &&
                         std::equal(current.begin(), current.end(), stages.begin());
    if (!appends) {
      throw Error("pipeline", "the database already has stage runs; a new pipeline may only "
                              "append stages to the current one",
                  {.file = path_.string(), .field = "pipeline"});
    }
  }
  Prepare("DELETE FROM pipeline").Run();
  for (size_t i = 0; i < stages.size(); ++i) {
    Prepare("INSERT INTO pipeline (position, stage) VALUES (?, ?)")
        .Bind(1, static_cast<std::int64_t>(i))
        .Bind(2, stages[i])
        .Run();
  }
  LogEvent(std::nullopt, "", "pipeline", "", Json(stages).dump());
  tx.Commit();
  pipeline_cache_ = stages;
}

std::vector<std::string> Database::Pipeline() {
  std::vector<std::string> stages;
  auto& q = Prepare("SELECT stage FROM pipeline ORDER BY position");
  while (q.Step()) stages.push_back(q.Text(0));
  q.Reset();
  pipeline_cache_ = stages;
  return stages;
}

int Database::StagePosition(const std::string& stage) {
  if (pipeline_cache_.empty()) Pipeline();
  const auto it = std::find(pipeline_cache_.begin(), pipeline_cache_.end(), stage);
  if (it == pipeline_cache_.end()) {
    Pipeline();  // another process may have appended stages
    const auto again = std::find(pipeline_cache_.begin(), pipeline_cache_.end(), stage);
    if (again == pipeline_cache_.end()) {
      throw Error("pipeline", "stage '" + stage + "' is not in this database's pipeline",
                  {.file = path_.string(), .field = "stage"});
    }
    return static_cast<int>(again - pipeline_cache_.begin());
  }
  return static_cast<int>(it - pipeline_cache_.begin());
}

// ---- Ingest -----------------------------------------------------------------

VideoId Database::UpsertVideo(const std::string& path_or_url) {
  const std::string stored = Store(path_or_url);
  auto& find = Prepare("SELECT id FROM videos WHERE path = ?");
  find.Bind(1, stored);
  if (find.Step()) {
    const VideoId id = find.Int(0);
    find.Reset();
    return id;
  }
  find.Reset();
  Prepare("INSERT INTO videos (path) VALUES (?)").Bind(1, stored).Run();
  return sqlite3_last_insert_rowid(db_);
}

Database::InsertResult Database::InsertClip(const ClipRecord& clip) {
  if (pipeline_cache_.empty()) Pipeline();
  if (pipeline_cache_.empty()) {
    throw Error("pipeline", "the database has no pipeline: run `doasido init` first",
                {.file = path_.string()});
  }
  auto& insert = Prepare(
      "INSERT OR IGNORE INTO clips (video_id, external_id, start_frame, end_frame, start_s, end_s,"
      " source_list, source_line, metadata, created_at) VALUES (?,?,?,?,?,?,?,?,?,?)");
  insert.Bind(1, clip.video_id)
      .Bind(2, clip.external_id)
      .Bind(3, clip.start_frame)
      .Bind(4, clip.end_frame)
      .Bind(5, clip.start_s)
      .Bind(6, clip.end_s)
      .Bind(7, clip.source_list)
      .Bind(8, static_cast<std::int64_t>(clip.source_line))
      .Bind(9, clip.metadata.dump())
      .Bind(10, Now())
      .Run();
  if (sqlite3_changes(db_) == 0) {
    auto& find = Prepare(
        "SELECT id FROM clips WHERE video_id = ? AND IFNULL(start_frame, -1) = IFNULL(?, -1) AND "
        "IFNULL(end_frame, -1) = IFNULL(?, -1) AND IFNULL(start_s, -1) = IFNULL(?, -1) AND "
        "IFNULL(end_s, -1) = IFNULL(?, -1)");
    find.Bind(1, clip.video_id)
        .Bind(2, clip.start_frame)
        .Bind(3, clip.end_frame)
        .Bind(4, clip.start_s)
        .Bind(5, clip.end_s);
    const ClipId id = find.Step() ? find.Int(0) : 0;
    find.Reset();
    return {id, false};
  }
  const ClipId id = sqlite3_last_insert_rowid(db_);
  Prepare("INSERT INTO stage_runs (clip_id, stage, position, state) VALUES (?, ?, 0, 'pending')")
      .Bind(1, id)
      .Bind(2, pipeline_cache_.front())
      .Run();
  return {id, true};
}

void Database::AddDetections(ClipId clip, const std::vector<Detection>& detections) {
  auto& insert = Prepare(
      "INSERT INTO detections (clip_id, frame, kind, x1, y1, x2, y2, score, contact_state,"
      " hand_side, dx, dy, magnitude, source) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
  for (const auto& d : detections) {
    insert.Bind(1, clip)
        .Bind(2, d.frame)
        .Bind(3, d.kind)
        .Bind(4, d.x1)
        .Bind(5, d.y1)
        .Bind(6, d.x2)
        .Bind(7, d.y2)
        .Bind(8, d.score)
        .Bind(9, d.contact_state)
        .Bind(10, d.hand_side)
        .Bind(11, d.dx)
        .Bind(12, d.dy)
        .Bind(13, d.magnitude)
        .Bind(14, d.source)
        .Run();
  }
}

void Database::LogEvent(std::optional<ClipId> clip, const std::string& stage,
                        const std::string& kind, const std::string& worker,
                        const std::string& detail) {
  Prepare("INSERT INTO events (at, clip_id, stage, kind, worker, detail) VALUES (?,?,?,?,?,?)")
      .Bind(1, Now())
      .Bind(2, clip)
      .Bind(3, stage)
      .Bind(4, kind)
      .Bind(5, worker)
      .Bind(6, detail)
      .Run();
}

// ---- Reading ----------------------------------------------------------------

ClipRecord Database::GetClip(ClipId id) {
  auto& q = Prepare(std::string("SELECT ") + db::kClipColumns + " FROM clips c WHERE c.id = ?");
  q.Bind(1, id);
  if (!q.Step()) {
    q.Reset();
    throw Error("no_such_clip", "no clip with this id", {.clip = std::to_string(id)});
  }
  ClipRecord c = db::ReadClipRow(q);
  q.Reset();
  return c;
}

VideoRecord Database::GetVideo(VideoId id) {
  auto& q = Prepare(
      "SELECT id, COALESCE(local_path, path), width, height, fps, frame_count, duration_s,"
      " variable_frame_rate, rotation_deg, codec, probed_at FROM videos WHERE id = ?");
  q.Bind(1, id);
  if (!q.Step()) {
    q.Reset();
    throw Error("no_such_video", "no video with id " + std::to_string(id));
  }
  VideoRecord v;
  v.id = q.Int(0);
  v.path = Resolve(q.Text(1)).string();
  if (!q.IsNull(10)) {
    VideoInfo info;
    info.width = static_cast<int>(q.Int(2));
    info.height = static_cast<int>(q.Int(3));
    info.fps = q.Real(4);
    info.frame_count = q.Int(5);
    info.duration_s = q.Real(6);
    info.variable_frame_rate = q.Int(7) != 0;
    info.rotation_deg = static_cast<int>(q.Int(8));
    info.codec = q.Text(9);
    v.info = info;
  }
  q.Reset();
  return v;
}

std::vector<Detection> Database::GetDetections(ClipId clip) {
  auto& q = Prepare(
      "SELECT frame, kind, x1, y1, x2, y2, score, contact_state, hand_side, dx, dy, magnitude,"
      " source FROM detections WHERE clip_id = ? ORDER BY frame, id");
  q.Bind(1, clip);
  std::vector<Detection> out;
  while (q.Step()) {
    Detection d;
    d.frame = q.Int(0);
    d.kind = q.Text(1);
    d.x1 = q.Real(2);
    d.y1 = q.Real(3);
    d.x2 = q.Real(4);
    d.y2 = q.Real(5);
    d.score = q.Real(6);
    d.contact_state = static_cast<int>(q.Int(7));
    d.hand_side = static_cast<int>(q.Int(8));
    d.dx = q.Real(9);
    d.dy = q.Real(10);
    d.magnitude = q.Real(11);
    d.source = q.Text(12);
    out.push_back(std::move(d));
  }
  q.Reset();
  return out;
}

std::optional<Json> Database::GetMeasurements(ClipId clip, const std::string& stage) {
  auto& q = Prepare("SELECT data FROM measurements WHERE clip_id = ? AND stage = ?");
  q.Bind(1, clip).Bind(2, stage);
  std::optional<Json> out;
  if (q.Step()) out = Json::parse(q.Text(0));
  q.Reset();
  return out;
}

ClipContext Database::LoadContext(ClipId clip, const std::string& stage) {
  ClipContext ctx;
  ctx.clip = GetClip(clip);
  ctx.video = GetVideo(ctx.clip.video_id);
  ctx.detections = GetDetections(clip);
  const int position = StagePosition(stage);
  auto& q = Prepare(
      "SELECT m.stage, m.data FROM measurements m JOIN pipeline p ON p.stage = m.stage"
      " WHERE m.clip_id = ? AND p.position < ?");
  q.Bind(1, clip).Bind(2, position);
  while (q.Step()) ctx.measurements[q.Text(0)] = Json::parse(q.Text(1));
  q.Reset();
  ctx.artifact_dir = ArtifactDir(clip, stage);
  return ctx;
}

std::int64_t Database::QueryInt(const std::string& sql) {
  auto& q = Prepare(sql);
  const std::int64_t n = q.Step() ? q.Int(0) : 0;
  q.Reset();
  return n;
}

std::int64_t Database::CountClips() { return QueryInt("SELECT COUNT(*) FROM clips"); }

std::int64_t Database::CountVideos() { return QueryInt("SELECT COUNT(*) FROM videos"); }

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
  if (result.verdict == Verdict::kPass) {
    QueueNextStage(claim.clip_id, claim.stage);
  } else {
    DropLaterStages(claim.clip_id, claim.stage);
  }
  LogEvent(claim.clip_id, claim.stage, "done", worker,
           std::string(ToString(result.verdict)) +
               (result.reason.empty() ? "" : " " + result.reason));
  tx.Commit();
  return true;
}

void Database::Fail(const Claim& claim, const std::string& worker, const std::string& error,
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
  if (sqlite3_changes(db_) > 0) {
    LogEvent(claim.clip_id, claim.stage, final ? "failed" : "retry", worker, error);
  }
  tx.Commit();
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

QueueSummary Database::Summary() {
  QueueSummary s;
  auto& q = Prepare(
      "SELECT state, COUNT(*), SUM(state = 'running' AND lease_expires < ?),"
      " SUM(clip_id IN (SELECT clip_id FROM shard_clips)) FROM stage_runs GROUP BY state");
  q.Bind(1, Now());
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
    out.push_back({q.Int(0), q.Int(1), q.Text(2), q.Text(3), q.Text(4),
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

// ---- Verdicts ---------------------------------------------------------------

void Database::SetVerdict(ClipId clip, const std::string& stage, Verdict verdict,
                          const std::string& reason, const std::string& source) {
  Transaction tx(*this);
  Prepare("UPDATE stage_runs SET verdict = ?, reason = ? WHERE clip_id = ? AND stage = ?"
          " AND state = 'done'")
      .Bind(1, ToString(verdict))
      .Bind(2, reason)
      .Bind(3, clip)
      .Bind(4, stage)
      .Run();
  if (sqlite3_changes(db_) == 0) {
    throw Error("not_done", "stage '" + stage + "' has not finished for this clip",
                {.clip = std::to_string(clip), .field = "stage"});
  }
  Prepare("INSERT INTO verdicts (clip_id, stage, verdict, reason, source, created_at)"
          " VALUES (?,?,?,?,?,?)")
      .Bind(1, clip)
      .Bind(2, stage)
      .Bind(3, ToString(verdict))
      .Bind(4, reason)
      .Bind(5, source)
      .Bind(6, Now())
      .Run();
  if (verdict == Verdict::kPass) {
    QueueNextStage(clip, stage);
  } else {
    DropLaterStages(clip, stage);
  }
  LogEvent(clip, stage, "verdict", source, std::string(ToString(verdict)) + " " + reason);
  tx.Commit();
}

bool Database::StoreRedecision(ClipId clip, const std::string& stage,
                               const std::string& param_hash, const StageResult& result,
                               bool changed) {
  Transaction tx(*this);
  auto& last = Prepare("SELECT source FROM verdicts WHERE clip_id = ? AND stage = ?"
                       " ORDER BY id DESC LIMIT 1");
  last.Bind(1, clip).Bind(2, stage);
  const bool human = last.Step() && last.Text(0) == "human";
  last.Reset();
  // A person's verdict stands; the run takes the new parameters so that the
  // worker does not run it again.
  auto& update = Prepare(human ? "UPDATE stage_runs SET param_hash = ? WHERE clip_id = ?"
                                 " AND stage = ? AND state = 'done'"
                               : "UPDATE stage_runs SET param_hash = ?, verdict = ?, reason = ?"
                                 " WHERE clip_id = ? AND stage = ? AND state = 'done'");
  update.Bind(1, param_hash);
  if (!human) update.Bind(2, ToString(result.verdict)).Bind(3, result.reason);
  update.Bind(human ? 2 : 4, clip).Bind(human ? 3 : 5, stage).Run();
  if (sqlite3_changes(db_) == 0 || human) {
    tx.Commit();
    return false;
  }
  const double now = Now();
  Prepare("UPDATE measurements SET param_hash = ?, data = ?, created_at = ?"
          " WHERE clip_id = ? AND stage = ?")
      .Bind(1, param_hash)
      .Bind(2, result.measurements.dump())
      .Bind(3, now)
      .Bind(4, clip)
      .Bind(5, stage)
      .Run();
  if (changed) {
    Prepare("INSERT INTO verdicts (clip_id, stage, verdict, reason, source, param_hash,"
            " created_at) VALUES (?,?,?,?,'rethreshold',?,?)")
        .Bind(1, clip)
        .Bind(2, stage)
        .Bind(3, ToString(result.verdict))
        .Bind(4, result.reason)
        .Bind(5, param_hash)
        .Bind(6, now)
        .Run();
    DropLaterStages(clip, stage);
    if (result.verdict == Verdict::kPass) QueueNextStage(clip, stage);
    LogEvent(clip, stage, "rethreshold", "",
             std::string(ToString(result.verdict)) + " " + result.reason);
  }
  tx.Commit();
  return true;
}

}  // namespace doasido
