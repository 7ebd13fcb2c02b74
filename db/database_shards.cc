// Shards: the queue split into self-contained databases and folded back.
//
// Both directions work on one connection with the other file ATTACHed as
// `shard`, so a shard is written, and a merge applied, in one transaction.
// Rows are copied by column lists below; clips keep their ids, so a clip's
// rows are found by clip_id on both sides.
#include <sqlite3.h>

#include <algorithm>
#include <functional>
#include <optional>
#include <set>
#include <tuple>

#include "db/database.h"
#include "db/statement.h"

namespace doasido {
namespace {

// Tables whose rows belong to one clip, with the columns that carry their
// content (row ids are local to each file and left out).
struct ClipTable {
  const char* name;
  const char* columns;
};
constexpr ClipTable kClipTables[] = {
    {"stage_runs",
     "clip_id, stage, position, state, attempts, lease_owner, lease_expires, param_hash, "
     "verdict, reason, started_at, finished_at, duration_s, error, inputs, requeued_by"},
    {"measurements", "clip_id, stage, param_hash, data, created_at"},
    {"verdicts", "clip_id, stage, verdict, reason, source, param_hash, created_at"},
    {"reviews", "clip_id, stage, reviewer, decision, reason, created_at"},
    {"artifacts", "clip_id, stage, kind, path, created_at"},
    {"detections",
     "clip_id, frame, kind, x1, y1, x2, y2, score, contact_state, hand_side, dx, dy, magnitude, "
     "source"},
};

// The stage_runs columns as a shard hands them over: a run some worker
// held when the file was copied is pending again, with no lease.
constexpr const char* kRunsHandedOver =
    "clip_id, stage, position, CASE state WHEN 'running' THEN 'pending' ELSE state END, "
    "attempts, CASE state WHEN 'running' THEN NULL ELSE lease_owner END, "
    "CASE state WHEN 'running' THEN NULL ELSE lease_expires END, param_hash, verdict, reason, "
    "started_at, finished_at, duration_s, error, inputs, requeued_by";

const char* SourceColumns(const ClipTable& t) {
  return std::string_view(t.name) == "stage_runs" ? kRunsHandedOver : t.columns;
}

// ATTACHes `file` as `shard` for the object's lifetime. SQLite refuses to
// attach or detach inside a transaction, so this wraps the transaction.
class Attached {
 public:
  Attached(sqlite3* db, const std::filesystem::path& file) : db_(db) {
    db::Statement attach(db_, "ATTACH DATABASE ? AS shard");
    attach.Bind(1, file.string());
    attach.Run();
  }
  ~Attached() { sqlite3_exec(db_, "DETACH DATABASE shard", nullptr, nullptr, nullptr); }

 private:
  sqlite3* db_;
};

std::string Rewrite(const std::string& path,
                    const std::vector<std::pair<std::string, std::string>>& media_map) {
  for (const auto& [from, to] : media_map) {
    if (path.rfind(from, 0) == 0) return to + path.substr(from.size());
  }
  return path;
}

// The SQL aggregate row_fingerprint(col, ...): the wrapping sum of a 64-bit
// hash of each row's values (type and bytes), so equal multisets of rows give
// equal fingerprints in any order. Merging compares clips by (fingerprint,
// row count) per table, one pass over the clip_id index on each side,
// instead of sorting every row's full content.
std::uint64_t HashValue(sqlite3_value* v, std::uint64_t h) {
  auto mix = [&h](const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;  // FNV-1a
  };
  const int type = sqlite3_value_type(v);
  mix(&type, sizeof type);
  if (type == SQLITE_INTEGER) {
    const sqlite3_int64 i = sqlite3_value_int64(v);
    mix(&i, sizeof i);
  } else if (type == SQLITE_FLOAT) {
    const double d = sqlite3_value_double(v);
    mix(&d, sizeof d);
  } else if (type != SQLITE_NULL) {
    const void* bytes = type == SQLITE_BLOB ? sqlite3_value_blob(v) : sqlite3_value_text(v);
    const int n = sqlite3_value_bytes(v);
    mix(&n, sizeof n);
    if (bytes) mix(bytes, static_cast<std::size_t>(n));
  }
  return h;
}
void FingerprintStep(sqlite3_context* ctx, int argc, sqlite3_value** argv) {
  auto* sum = static_cast<std::uint64_t*>(sqlite3_aggregate_context(ctx, sizeof(std::uint64_t)));
  if (!sum) return sqlite3_result_error_nomem(ctx);
  std::uint64_t h = 14695981039346656037ull;
  for (int i = 0; i < argc; ++i) h = HashValue(argv[i], h);
  *sum += h;
}
void FingerprintFinal(sqlite3_context* ctx) {
  auto* sum = static_cast<std::uint64_t*>(sqlite3_aggregate_context(ctx, 0));
  sqlite3_result_int64(ctx, sum ? static_cast<sqlite3_int64>(*sum) : 0);
}
void RegisterFingerprint(sqlite3* db) {
  sqlite3_create_function_v2(db, "row_fingerprint", -1, SQLITE_UTF8 | SQLITE_DETERMINISTIC,
                             nullptr, nullptr, FingerprintStep, FingerprintFinal, nullptr);
}

// A count over the attached file; not cached, so nothing holds it at DETACH.
std::int64_t Count(sqlite3* db, const std::string& sql) {
  db::Statement q(db, sql);
  return q.Step() ? q.Int(0) : 0;
}

// temp.selected holds `clips`, the clips a shard operation is about.
void SelectClips(sqlite3* db, const std::vector<ClipId>& clips) {
  db::Exec(db, "CREATE TEMP TABLE IF NOT EXISTS selected (clip_id INTEGER PRIMARY KEY);"
               "DELETE FROM temp.selected;");
  db::Statement add(db, "INSERT INTO temp.selected VALUES (?)");
  for (ClipId c : clips) add.Bind(1, c).Run();
}

std::string ShardMeta(sqlite3* db, const std::string& key) {
  db::Statement q(db, "SELECT value FROM shard.meta WHERE key = ?");
  q.Bind(1, key);
  return q.Step() ? q.Text(0) : std::string();
}


// The steps of Database::MergeShard, each on the connection with the shard
// attached as schema "shard", inside the merge's transaction.

// Attaches `file` as schema "shard"; any error is the shard's (not a
// doasido shard database), not this database's.
void AttachShard(sqlite3* db, const std::filesystem::path& file, const std::string& where,
                 std::optional<Attached>& attached) {
  try {
    attached.emplace(db, file);
    if (Count(db, "SELECT COUNT(*) FROM shard.sqlite_master WHERE name = 'meta'") == 0) {
      throw Error("not_a_shard", "");
    }
  } catch (const Error& e) {
    throw Error("not_a_shard",
                "not a doasido shard database (made by doasido shard)" +
                    (e.message().empty() ? std::string() : ": " + e.message()),
                {.file = where});
  }
}

// This database's row for the attached shard.
struct ShardEntry {
  std::string name;
  std::int64_t id = 0;
  std::string config_hash;
};

// The attached shard's entry, after checking that it was split from this
// database (`uuid`) and runs its `pipeline`.
ShardEntry CheckShardIsOurs(sqlite3* db, const std::string& uuid,
                            const std::vector<std::string>& pipeline, const std::string& where) {
  ShardEntry entry;
  entry.name = ShardMeta(db, "shard_name");
  if (entry.name.empty()) {
    throw Error("not_a_shard", "not a doasido shard database (made by doasido shard)",
                {.file = where});
  }
  if (ShardMeta(db, "parent_uuid") != uuid) {
    throw Error("foreign_shard",
                "shard " + entry.name + " was split from another database (" +
                    ShardMeta(db, "parent_path") + ")",
                {.file = where});
  }
  db::Statement q(db, "SELECT id, config_hash FROM shards WHERE name = ?");
  q.Bind(1, entry.name);
  if (q.Step()) {
    entry.id = q.Int(0);
    entry.config_hash = q.Text(1);
  }
  if (entry.id == 0) {
    throw Error("foreign_shard", "this database lists no shard named " + entry.name,
                {.file = where});
  }
  std::vector<std::string> theirs;
  db::Statement stages(db, "SELECT stage FROM shard.pipeline ORDER BY position");
  while (stages.Step()) theirs.push_back(stages.Text(0));
  if (theirs != pipeline) {
    throw Error("pipeline_mismatch",
                "shard " + entry.name + " runs pipeline " + Json(theirs).dump() +
                    ", this database " + Json(pipeline).dump(),
                {.file = where, .field = "pipeline"});
  }
  return entry;
}

// The shard's stage parameter hashes, checked against the configuration
// this database recorded for it.
Json CheckShardConfig(sqlite3* db, const ShardEntry& entry, const std::string& where) {
  Json hashes = Json::parse(ShardMeta(db, "stage_hashes"), nullptr, false);
  if (hashes.is_discarded() || ParamHash(hashes) != entry.config_hash) {
    throw Error("config_mismatch",
                "shard " + entry.name + " was made with another configuration than this "
                "database recorded for it",
                {.file = where, .field = "stage_hashes"});
  }
  return hashes;
}

// temp.selected: the shard's clips but those held back.
void SelectShardClips(sqlite3* db, std::int64_t shard_id, const std::set<ClipId>& hold_back) {
  db::Exec(db, "CREATE TEMP TABLE IF NOT EXISTS selected (clip_id INTEGER PRIMARY KEY);"
               "DELETE FROM temp.selected;");
  db::Statement select(db, "INSERT INTO temp.selected SELECT clip_id FROM shard_clips"
                           " WHERE shard_id = ?");
  select.Bind(1, shard_id).Run();
  db::Statement drop(db, "DELETE FROM temp.selected WHERE clip_id = ?");
  for (ClipId clip : hold_back) {
    drop.Bind(1, clip).Run();
  }
}

// Refuses a shard whose finished runs used other stage parameters than it
// was made for.
void CheckRunParameters(sqlite3* db, const Json& hashes, const std::string& shard,
                        const std::string& where) {
  db::Statement runs(db, "SELECT stage, param_hash FROM shard.stage_runs"
                         " WHERE state = 'done' AND clip_id IN temp.selected");
  while (runs.Step()) {
    const std::string stage = runs.Text(0);
    const std::string hash = runs.IsNull(1) ? "" : runs.Text(1);
    if (hashes.contains(stage) && hashes[stage] != hash) {
      throw Error("config_mismatch",
                  "shard " + shard + " ran stage " + stage + " with parameters " + hash +
                      "; it was made for " + hashes[stage].get<std::string>() +
                      " (run it with the --config it was sharded with)",
                  {.file = where, .field = stage});
    }
  }
}

// Replaces, table by table, the rows of every selected clip whose rows
// differ from the shard's (as multisets of content). Returns how many
// clips changed.
std::int64_t MergeClipRows(sqlite3* db) {
  RegisterFingerprint(db);
  db::Exec(db, "CREATE TEMP TABLE IF NOT EXISTS changed (clip_id INTEGER PRIMARY KEY);"
               "CREATE TEMP TABLE IF NOT EXISTS differing (clip_id INTEGER PRIMARY KEY);"
               "DELETE FROM temp.changed;");
  for (const ClipTable& t : kClipTables) {
    auto per_clip = [&t](const std::string& schema, const char* columns) {
      return "SELECT clip_id, row_fingerprint(" + std::string(columns) + "), COUNT(*) FROM " +
             schema + "." + t.name + " WHERE clip_id IN temp.selected GROUP BY clip_id";
    };
    const std::string mine = per_clip("main", t.columns);
    const std::string theirs = per_clip("shard", SourceColumns(t));
    db::Exec(db, "DELETE FROM temp.differing;");
    db::Exec(db, "INSERT INTO temp.differing SELECT clip_id FROM (" + mine + " EXCEPT " +
                     theirs + ") UNION SELECT clip_id FROM (" + theirs + " EXCEPT " + mine + ")");
    db::Exec(db, std::string("DELETE FROM main.") + t.name + " WHERE clip_id IN temp.differing");
    db::Exec(db, std::string("INSERT INTO main.") + t.name + " (" + t.columns + ") SELECT " +
                     SourceColumns(t) + " FROM shard." + t.name +
                     " WHERE clip_id IN temp.differing ORDER BY rowid");
    db::Exec(db, "INSERT OR IGNORE INTO temp.changed SELECT clip_id FROM temp.differing");
  }
  return Count(db, "SELECT COUNT(*) FROM temp.changed");
}

// What probing learnt about the selected clips' videos (their paths stay
// this database's), and the files the shard downloaded (in `shard_root`,
// stored through `store`).
void MergeVideos(sqlite3* db, const std::filesystem::path& shard_root,
                 const std::function<std::string(const std::string&)>& store) {
  db::Exec(db,
           "UPDATE main.videos SET (width, height, fps, frame_count, duration_s,"
           " variable_frame_rate, rotation_deg, codec, probed_at) ="
           " (SELECT width, height, fps, frame_count, duration_s, variable_frame_rate,"
           "         rotation_deg, codec, probed_at FROM shard.videos s WHERE s.id = videos.id)"
           " WHERE id IN (SELECT video_id FROM main.clips WHERE id IN temp.selected)"
           "   AND EXISTS (SELECT 1 FROM shard.videos s WHERE s.id = videos.id AND"
           "     (s.width, s.height, s.fps, s.frame_count, s.duration_s, s.variable_frame_rate,"
           "      s.rotation_deg, s.codec, s.probed_at) IS NOT (videos.width, videos.height,"
           "      videos.fps, videos.frame_count, videos.duration_s, videos.variable_frame_rate,"
           "      videos.rotation_deg, videos.codec, videos.probed_at))");
  db::Statement local(db, "SELECT id, local_path, size_bytes, sha256, downloaded_at"
                          " FROM shard.videos WHERE local_path IS NOT NULL AND id IN"
                          " (SELECT video_id FROM main.clips WHERE id IN temp.selected)");
  db::Statement update(db, "UPDATE main.videos SET local_path = ?, size_bytes = ?, sha256 = ?,"
                           " downloaded_at = ? WHERE id = ? AND (local_path, size_bytes, sha256,"
                           " downloaded_at) IS NOT (?, ?, ?, ?)");
  while (local.Step()) {
    std::filesystem::path p = local.Text(1);
    if (p.is_relative()) p = shard_root / p;
    const std::string stored = store(p.lexically_normal().string());
    update.Bind(1, stored).Bind(2, local.OptInt(2)).Bind(3, local.IsNull(3) ? "" : local.Text(3));
    update.Bind(4, local.OptReal(4)).Bind(5, local.Int(0)).Bind(6, stored);
    update.Bind(7, local.OptInt(2)).Bind(8, local.IsNull(3) ? "" : local.Text(3));
    update.Bind(9, local.OptReal(4)).Run();
  }
}

// Copies the shard's events since the last merge; a shard with no open run
// hands its clips back and is marked merged into `parent`.
void MergeEvents(sqlite3* db, std::int64_t shard_id, const std::string& parent,
                 Database::MergeStats& stats) {
  db::Statement last(db, "SELECT merged_event FROM shards WHERE id = ?");
  last.Bind(1, shard_id);
  last.Step();
  const std::int64_t from = last.Int(0);
  db::Statement events(db, "INSERT INTO main.events (at, clip_id, stage, kind, worker, detail)"
                           " SELECT at, clip_id, stage, kind, worker, detail FROM shard.events"
                           " WHERE id > ? AND (clip_id IS NULL OR clip_id IN temp.selected)"
                           " AND kind NOT IN ('pipeline') ORDER BY id");
  events.Bind(1, from).Run();
  stats.events = sqlite3_changes(db);
  if (stats.open_runs == 0) {
    // Finished: the clips are this database's again (re-queue, re-shard
    // and its workers treat them as any clip), and the shard takes no
    // more runs (RefuseMergedShard), so nothing it does later competes.
    db::Statement hand_back(db, "DELETE FROM shard_clips WHERE shard_id = ?");
    hand_back.Bind(1, shard_id).Run();
    stats.handed_back = sqlite3_changes(db);
    db::Statement mark(db, "INSERT OR REPLACE INTO shard.meta (key, value) VALUES (?, ?)");
    mark.Bind(1, Database::kMergedIntoKey).Bind(2, parent).Run();
  }
  if (stats.events > 0 || stats.changed_clips > 0) {
    db::Statement update(db, "UPDATE shards SET merged_at = ?, merged_event ="
                             " (SELECT COALESCE(MAX(id), 0) FROM shard.events) WHERE id = ?");
    update.Bind(1, Now()).Bind(2, shard_id).Run();
  }
}

}  // namespace

std::string Database::Uuid() { return GetMeta("uuid").value_or(""); }

std::optional<std::string> Database::GetMeta(const std::string& key) {
  auto& q = Prepare("SELECT value FROM meta WHERE key = ?");
  q.Bind(1, key);
  std::optional<std::string> value;
  if (q.Step()) value = q.Text(0);
  q.Reset();
  return value;
}

void Database::SetMeta(const std::string& key, const std::string& value) {
  Prepare("INSERT INTO meta (key, value) VALUES (?, ?)"
          " ON CONFLICT(key) DO UPDATE SET value = excluded.value")
      .Bind(1, key)
      .Bind(2, value)
      .Run();
}

std::vector<Database::ShardCandidate> Database::ShardCandidates() {
  auto& q = Prepare(
      "SELECT c.id, c.video_id,"
      "       COALESCE(c.end_frame - c.start_frame + 1,"
      "                CAST((c.end_s - c.start_s) * v.fps AS INTEGER), v.frame_count, 1)"
      " FROM clips c JOIN videos v ON v.id = c.video_id"
      " WHERE c.id NOT IN (SELECT clip_id FROM shard_clips)"
      "   AND EXISTS (SELECT 1 FROM stage_runs r WHERE r.clip_id = c.id"
      "               AND r.state IN ('pending', 'running', 'failed'))"
      " ORDER BY c.id");
  std::vector<ShardCandidate> out;
  while (q.Step()) out.push_back({q.Int(0), q.Int(1), std::max<std::int64_t>(1, q.Int(2))});
  q.Reset();
  return out;
}

void Database::WriteShardDatabase(const ShardSpec& spec, const std::filesystem::path& file) {
  for (const auto& p : {spec.path, file}) {
    if (std::filesystem::exists(p)) {
      throw Error("shard_exists", "the shard database already exists: remove it or pick --out",
                  {.file = p.string()});
    }
  }
  for (ClipId c : spec.clips) {
    auto& q = Prepare("SELECT shard_id FROM shard_clips WHERE clip_id = ?");
    q.Bind(1, c);
    const bool taken = q.Step();
    q.Reset();
    if (taken) {
      throw Error("already_sharded", "clip " + std::to_string(c) + " is already in a shard",
                  {.file = path_.string()});
    }
  }
  try {
    WriteShard(spec, file);
  } catch (...) {
    for (const char* suffix : {"", "-wal", "-shm"}) {
      std::error_code ec;
      std::filesystem::remove(file.string() + suffix, ec);
    }
    throw;
  }
}

bool Database::UnlistedShardOf(const std::filesystem::path& shard_db) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(shard_db, ec)) return false;
  for (const ShardRow& row : ListShards()) {
    if (std::filesystem::equivalent(row.path, shard_db, ec)) return false;
  }
  try {
    Attached attached(db_, shard_db);
    return ShardMeta(db_, "parent_uuid") == Uuid();
  } catch (const Error&) {
    return false;
  }
}

void Database::WriteShard(const ShardSpec& spec, const std::filesystem::path& file) {
  {
    Database shard(file, busy_timeout_s_);  // creates the schema
    shard.SetPipeline(Pipeline(), FlagContinuing());
    shard.SetMeta("parent_uuid", Uuid());
    shard.SetMeta("parent_path", path_.string());
    shard.SetMeta("shard_name", spec.name);
    shard.SetMeta("stage_hashes", spec.stage_hashes.dump());
  }
  Attached attached(db_, file);
  Transaction tx(*this);
  SelectClips(db_, spec.clips);
  db::Exec(db_, "INSERT INTO shard.videos SELECT * FROM videos"
                " WHERE id IN (SELECT video_id FROM clips WHERE id IN temp.selected)");
  {
    // Stored paths are relative to this database's folder; the shard lives
    // elsewhere, so it gets absolute (or remapped) ones.
    db::Statement videos(db_, "SELECT id, path, local_path FROM shard.videos");
    db::Statement update(db_, "UPDATE shard.videos SET path = ?, local_path = ? WHERE id = ?");
    std::vector<std::tuple<VideoId, std::string, std::optional<std::string>>> rows;
    while (videos.Step()) {
      rows.emplace_back(videos.Int(0), videos.Text(1),
                        videos.IsNull(2) ? std::nullopt : std::optional(videos.Text(2)));
    }
    for (const auto& [id, stored, local] : rows) {
      update.Bind(1, Rewrite(Resolve(stored).string(), spec.media_map));
      if (local) {
        update.Bind(2, Rewrite(Resolve(*local).string(), spec.media_map));
      } else {
        update.BindNull(2);
      }
      update.Bind(3, id).Run();
    }
  }
  db::Exec(db_, "INSERT INTO shard.clips SELECT * FROM clips WHERE id IN temp.selected");
  for (const ClipTable& t : kClipTables) {
    db::Exec(db_, std::string("INSERT INTO shard.") + t.name + " (" + t.columns + ") SELECT " +
                      SourceColumns(t) + " FROM " + t.name +
                      " WHERE clip_id IN temp.selected ORDER BY rowid");
  }
  tx.Commit();
}

void Database::RegisterShard(const ShardSpec& spec, const std::function<void()>& before_commit) {
  Transaction tx(*this);
  SelectClips(db_, spec.clips);
  Prepare("INSERT INTO shards (name, path, config_hash, clips, frames, created_at)"
          " VALUES (?, ?, ?, ?, ?, ?)")
      .Bind(1, spec.name)
      .Bind(2, Store(spec.path.string()))
      .Bind(3, ParamHash(spec.stage_hashes))
      .Bind(4, static_cast<std::int64_t>(spec.clips.size()))
      .Bind(5, spec.frames)
      .Bind(6, Now())
      .Run();
  Prepare("INSERT INTO shard_clips SELECT clip_id, ? FROM temp.selected")
      .Bind(1, static_cast<std::int64_t>(sqlite3_last_insert_rowid(db_)))
      .Run();
  LogEvent(std::nullopt, "", "shard", "",
           Json{{"shard", spec.name}, {"clips", spec.clips.size()}}.dump());
  if (before_commit) before_commit();
  tx.Commit();
}

std::vector<Database::ShardRow> Database::ListShards() {
  auto& q = Prepare("SELECT id, name, path, config_hash, clips, frames, created_at, merged_at,"
                    " slurm_job, slurm_task FROM shards ORDER BY id");
  std::vector<ShardRow> out;
  while (q.Step()) {
    out.push_back({q.Int(0), q.Text(1), Resolve(q.Text(2)), q.Text(3), q.Int(4), q.Int(5),
                   q.Real(6), q.OptReal(7), q.IsNull(8) ? "" : q.Text(8), q.OptInt(9)});
  }
  q.Reset();
  return out;
}

void Database::SetShardJob(const std::string& name, const std::string& job, std::int64_t task) {
  Prepare("UPDATE shards SET slurm_job = ?, slurm_task = ? WHERE name = ?")
      .Bind(1, job)
      .Bind(2, task)
      .Bind(3, name)
      .Run();
}

Database::MergeStats Database::MergeShard(const std::filesystem::path& file,
                                          const std::set<ClipId>& hold_back,
                                          const std::string& placement) {
  const std::string where = std::filesystem::absolute(file).string();
  if (!std::filesystem::is_regular_file(file)) {
    throw Error("not_a_shard", "no such shard database", {.file = where});
  }
  std::error_code ec;
  if (std::filesystem::equivalent(file, path_, ec)) {
    throw Error("self_merge", "this is the database being merged into, not a shard of it",
                {.file = where});
  }
  std::optional<Attached> attached;
  AttachShard(db_, file, where, attached);
  Transaction tx(*this);
  MergeStats stats;
  const ShardEntry entry = CheckShardIsOurs(db_, Uuid(), Pipeline(), where);
  stats.shard = entry.name;
  const Json hashes = CheckShardConfig(db_, entry, where);
  SelectShardClips(db_, entry.id, hold_back);
  CheckRunParameters(db_, hashes, entry.name, where);
  stats.changed_clips = MergeClipRows(db_);
  MergeVideos(db_, std::filesystem::absolute(file).parent_path(),
              [this](const std::string& path) { return Store(path); });
  stats.clips = QueryInt("SELECT COUNT(*) FROM temp.selected");
  stats.finished_runs = Count(db_, 
      "SELECT COUNT(*) FROM shard.stage_runs WHERE state IN ('done', 'failed')"
      " AND clip_id IN temp.selected");
  stats.open_runs = Count(db_, 
      "SELECT COUNT(*) FROM shard.stage_runs WHERE state IN ('pending', 'running')"
      " AND clip_id IN temp.selected");
  MergeEvents(db_, entry.id, std::filesystem::absolute(path_).string(), stats);
  if (!placement.empty() && stats.clips > 0) {  // else the clips are this database's already
    Prepare("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)")
        .Bind(1, kPlacementKey)
        .Bind(2, placement)
        .Run();
  }
  tx.Commit();
  return stats;
}

std::int64_t Database::ReleaseLeases() {
  Transaction tx(*this);
  Prepare("INSERT INTO events (at, clip_id, stage, kind, worker, detail)"
          " SELECT ?, clip_id, stage, 'release', lease_owner, 'lease released'"
          " FROM stage_runs WHERE state = 'running'")
      .Bind(1, Now())
      .Run();
  Prepare("UPDATE stage_runs SET state = 'pending', lease_owner = NULL, lease_expires = NULL"
          " WHERE state = 'running'")
      .Run();
  const std::int64_t n = sqlite3_changes(db_);
  tx.Commit();
  return n;
}

}  // namespace doasido
