#include "db/database.h"

#include <sqlite3.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <set>
#include <thread>

#include "core/error_codes.h"

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

const char* ToString(RunState s) {
  switch (s) {
    case RunState::kPending: return "pending";
    case RunState::kRunning: return "running";
    case RunState::kDone: return "done";
    case RunState::kFailed: return "failed";
  }
  return "?";
}

RunState ParseRunState(std::string_view text) {
  for (RunState s : {RunState::kPending, RunState::kRunning, RunState::kDone, RunState::kFailed}) {
    if (text == ToString(s)) return s;
  }
  throw Error("database", "unknown stage-run state '" + std::string(text) + "'");
}

namespace {

// `path` as the path of an SQLite URI (RFC 3986: %, ? and # escaped).
std::string UriPath(const std::filesystem::path& path) {
  std::string out;
  for (const char c : path.string()) {
    if (c == '%' || c == '?' || c == '#') {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", static_cast<unsigned char>(c));
      out += hex;
    } else {
      out += c;
    }
  }
  return out;
}

// Said once per file and process: a command opens its database more than once.
void SayReadOnly(const std::filesystem::path& path, bool folder) {
  static std::set<std::string> said;
  if (!said.insert(path.string()).second) return;
  std::fprintf(stderr, "opened %s read-only (%s): nothing will be written to it\n", path.c_str(),
               folder ? "its folder cannot be written: a read-only filesystem or folder"
                      : "the file cannot be written");
}

}  // namespace

Database::Database(const std::filesystem::path& path, double busy_timeout_s, OpenMode mode)
    : busy_timeout_s_(busy_timeout_s) {
  path_ = std::filesystem::absolute(path).lexically_normal();
  root_ = path_.parent_path();
  if (!std::filesystem::exists(root_)) {
    throw Error("database", "folder does not exist", {.file = path_.string()});
  }
  if (mode == OpenMode::kExisting && !std::filesystem::is_regular_file(path_)) {
    throw Error("no_database",
                "no doasido database here (doasido init or doasido ingest creates one)",
                {.file = path_.string()});
  }
  // A database nobody may write (a read-only mount, a write-protected file)
  // is opened read-only and said so; every write then fails with
  // Error(kReadOnly) naming the file. access(W_OK) decides, so a read-only
  // mount counts for root too (a chmod does not stop root, nor this).
  const bool exists = std::filesystem::is_regular_file(path_);
  const bool folder_read_only = access(root_.c_str(), W_OK) != 0;
  read_only_ = exists && (folder_read_only || access(path_.c_str(), W_OK) != 0);
  const int flags =
      read_only_ ? SQLITE_OPEN_READONLY | SQLITE_OPEN_URI
                 : SQLITE_OPEN_READWRITE | (mode == OpenMode::kCreate ? SQLITE_OPEN_CREATE : 0);
  // On a read-only folder SQLite cannot make the WAL's -shm file; nothing
  // can change the file there, which is what immutable=1 tells it.
  const std::string name = !read_only_ ? path_.string()
                           : folder_read_only ? "file:" + UriPath(path_) + "?immutable=1"
                                              : "file:" + UriPath(path_) + "?mode=ro";
  if (read_only_) SayReadOnly(path_, folder_read_only);
  if (sqlite3_open_v2(name.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw Error("database", "cannot open: " + message, {.file = path_.string()});
  }
  static thread_local BusyState busy_state;
  busy_state.timeout_s = busy_timeout_s_;
  sqlite3_busy_handler(db_, BusyHandler, &busy_state);
  try {
    RefuseForeign();
    // WAL lets readers and one writer work at once; NORMAL sync is durable
    // against process crashes (a killed worker), which is what the queue
    // must survive. Reads go through mmap to spare a copy per page.
    if (!read_only_) db::Exec(db_, "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;");
    db::Exec(db_, "PRAGMA foreign_keys=ON; PRAGMA mmap_size=268435456; PRAGMA cache_size=-65536;");
    Migrate();
    OpenArtifactRoot();
    if (!read_only_) {
      FinishPlacement();  // a merge killed after its commit
    } else if (GetMeta(kPlacementKey)) {
      std::fprintf(stderr, "warning: a merge into %s did not finish placing its folders, and a "
                   "read-only database cannot finish it: some merged runs may lack their folders\n",
                   path_.c_str());
    }
  } catch (const Error& e) {
    // Statements still prepared keep sqlite3_close from closing (found by
    // LeakSanitizer: every refused foreign database leaked its connection).
    statements_.clear();
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

void Database::RefuseForeign() {
  int id = 0;
  try {
    id = static_cast<int>(QueryInt("PRAGMA application_id"));
  } catch (const Error&) {
    if (sqlite3_errcode(db_) != SQLITE_NOTADB) throw;
    throw Error("foreign_database", "not a doasido database (not an SQLite file at all)");
  }
  const bool empty = QueryInt("SELECT COUNT(*) FROM sqlite_master") == 0;
  const bool ours_before_the_mark =
      id == 0 &&
      QueryInt("SELECT COUNT(*) FROM sqlite_master WHERE name = 'schema_version'") > 0;
  if (id == kApplicationId) return;
  if (id != 0 || (!empty && !ours_before_the_mark)) {
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%08x", static_cast<unsigned>(id));
    throw Error("foreign_database",
                std::string("not a doasido database (SQLite application_id ") + hex +
                    (id == 0 ? ", tables of another program" : "") +
                    "); nothing was written to it");
  }
  if (!read_only_) db::Exec(db_, "PRAGMA application_id = " + std::to_string(kApplicationId));
}

void Database::Migrate() {
  if (read_only_) {
    const int version =
        QueryInt("SELECT COUNT(*) FROM sqlite_master WHERE name = 'schema_version'") > 0
            ? SchemaVersion()
            : 0;
    if (version != LatestSchemaVersion()) {
      throw Error(kReadOnly, "the database is read-only and its schema (version " +
                                 std::to_string(version) + ") is not this doasido's (" +
                                 std::to_string(LatestSchemaVersion()) +
                                 "): open it once where it can be written");
    }
    return;
  }
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

void Database::SetPipeline(const std::vector<std::string>& stages,
                           const std::set<std::string>& flag_continues) {
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
    Prepare("INSERT INTO pipeline (position, stage, flag_continues) VALUES (?, ?, ?)")
        .Bind(1, static_cast<std::int64_t>(i))
        .Bind(2, stages[i])
        .Bind(3, flag_continues.count(stages[i]) ? 1 : 0)
        .Run();
  }
  LogEvent(std::nullopt, "", "pipeline", "", Json(stages).dump());
  tx.Commit();
  Pipeline();
}

std::vector<std::string> Database::Pipeline() {
  std::vector<std::string> stages;
  std::set<std::string> continues;
  auto& q = Prepare("SELECT stage, flag_continues FROM pipeline ORDER BY position");
  while (q.Step()) {
    stages.push_back(q.Text(0));
    if (q.Int(1) != 0) continues.insert(q.Text(0));
  }
  q.Reset();
  pipeline_cache_ = stages;
  flag_continues_cache_ = continues;
  return stages;
}

std::set<std::string> Database::FlagContinuing() {
  Pipeline();
  return flag_continues_cache_;
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

}  // namespace doasido
