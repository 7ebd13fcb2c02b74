// The doasido database: one SQLite file (WAL) that holds the clips, the
// stage queue and everything the stages measured. This class owns every SQL
// statement of the project; nothing else opens the file.
//
// Paths of local videos and artifacts are stored relative to the database's
// folder, so the folder can be moved as a whole; the API takes and returns
// absolute paths. URLs are stored as given.
//
// Concurrency: any number of processes may open the same file. Each write
// is one short `BEGIN IMMEDIATE` transaction; a busy database is retried for
// up to `busy_timeout_s`. A Database object belongs to one thread.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "db/records.h"
#include "db/stage.h"

struct sqlite3;

namespace doasido {

namespace db {
class Statement;
}

enum class RunState { kPending, kRunning, kDone, kFailed };
const char* ToString(RunState s);

// A stage run handed to a worker.
struct Claim {
  std::int64_t run_id = 0;
  ClipId clip_id = 0;
  std::string stage;
  int attempts = 0;  // including this one
};

struct StageRunRow {
  std::int64_t run_id = 0;
  ClipId clip_id = 0;
  std::string external_id;
  std::string stage;
  std::string state;
  int attempts = 0;
  std::string verdict;  // empty until decided
  std::string reason;
  std::string error;
  std::string lease_owner;
  double duration_s = 0;
};

// One cell of `doasido status`: clips of a stage in a state with a verdict.
struct StageCount {
  std::string stage;
  std::string state;
  std::string verdict;  // empty for runs without a verdict
  std::string reason;
  std::int64_t count = 0;
};

struct RunFilter {
  std::string stage;               // empty: all stages
  std::string state;               // empty: all states
  std::optional<ClipId> clip;      // empty: all clips
  int limit = 0;                   // 0: no limit
};

struct QueueSummary {
  std::int64_t pending = 0, running = 0, done = 0, failed = 0;
  std::int64_t expired = 0;  // running with an expired lease
};

class Database {
 public:
  // Opens or creates the file and upgrades its schema. Throws Error
  // ("database") naming the file when it cannot, or when the schema is
  // newer than this program understands.
  explicit Database(const std::filesystem::path& path, double busy_timeout_s = 60.0);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // The folder relative paths are resolved against.
  const std::filesystem::path& root() const { return root_; }
  int SchemaVersion();
  static int LatestSchemaVersion();

  // <root>/artifacts/<clip>/<stage>/ (not created).
  std::filesystem::path ArtifactDir(ClipId clip, const std::string& stage) const;
  // Absolute form of a stored path, and stored form of a path.
  std::filesystem::path Resolve(const std::string& stored) const;
  std::string Store(const std::string& path_or_url) const;

  // ---- Transactions -------------------------------------------------------
  // RAII `BEGIN IMMEDIATE`; rolls back unless Commit() was called. Inside
  // an open transaction it is a savepoint, so calls that each guard their
  // own writes compose: a worker completes one run and claims the next in
  // a single commit.
  class Transaction {
   public:
    explicit Transaction(Database& db);
    ~Transaction();
    void Commit();

   private:
    Database& db_;
    bool nested_;
    bool done_ = false;
  };

  // ---- Pipeline -----------------------------------------------------------
  // The ordered stages every clip goes through. Setting it on a database
  // that already has stage runs is allowed only to append stages.
  void SetPipeline(const std::vector<std::string>& stages);
  std::vector<std::string> Pipeline();

  // ---- Ingest -------------------------------------------------------------
  VideoId UpsertVideo(const std::string& path_or_url);
  struct InsertResult {
    ClipId id = 0;
    bool inserted = false;  // false: the same video and span was already there
  };
  // Inserts a clip (deduplicated by video and span) and queues it for the
  // first pipeline stage. Call inside a Transaction for bulk loads.
  InsertResult InsertClip(const ClipRecord& clip);
  void AddDetections(ClipId clip, const std::vector<Detection>& detections);
  void LogEvent(std::optional<ClipId> clip, const std::string& stage, const std::string& kind,
                const std::string& worker, const std::string& detail);

  // ---- Reading ------------------------------------------------------------
  ClipRecord GetClip(ClipId id);
  VideoRecord GetVideo(VideoId id);
  std::vector<Detection> GetDetections(ClipId clip);
  std::optional<Json> GetMeasurements(ClipId clip, const std::string& stage);
  // Everything a stage needs to run on `clip` (artifact_dir not created).
  ClipContext LoadContext(ClipId clip, const std::string& stage);
  std::int64_t CountClips();
  std::int64_t CountVideos();

  // ---- Queue --------------------------------------------------------------
  // Claims the oldest pending run (or a run whose lease expired) of one of
  // `stages` (all when empty) for `worker`, leased for `lease_s` seconds.
  // A run whose attempts reached `max_attempts` is failed instead of handed
  // out. Returns nullopt when nothing is claimable right now.
  std::optional<Claim> ClaimNext(const std::string& worker, const std::vector<std::string>& stages,
                                 double lease_s, int max_attempts);
  // Extends the lease; false when the worker no longer holds it.
  bool Heartbeat(std::int64_t run_id, const std::string& worker, double lease_s);
  // Records the result and marks the run done, queueing the clip for the
  // next stage when the verdict is pass. Returns false (and changes nothing)
  // when `worker` no longer holds the lease: the run was reclaimed and its
  // result belongs to whoever holds it now.
  bool Complete(const Claim& claim, const std::string& worker, const std::string& param_hash,
                const StageResult& result, double duration_s);
  // Records a failed attempt: back to pending while attempts < max_attempts,
  // else failed. The error text is kept either way.
  void Fail(const Claim& claim, const std::string& worker, const std::string& error,
            int max_attempts);
  // Done or failed runs of `stage` whose parameters differ from
  // `param_hash` go back to pending (new parameters: re-run; same: no-op).
  std::int64_t InvalidateOtherParams(const std::string& stage, const std::string& param_hash);
  // failed -> pending with attempts reset. Empty stage: all stages.
  std::int64_t Retry(const std::string& stage, std::optional<ClipId> clip);
  // Any state -> pending with attempts reset, and the clip's later stages
  // dropped. Empty stage is not allowed.
  std::int64_t Reset(const std::string& stage, std::optional<ClipId> clip);
  QueueSummary Summary();
  std::vector<StageCount> Counts();
  std::vector<StageRunRow> ListRuns(const RunFilter& filter);
  // Number of 'done' events per clip and stage (an audit of exactly-once).
  std::map<std::pair<ClipId, std::string>, int> DoneEventCounts();

  // ---- Verdicts -----------------------------------------------------------
  // Replaces the current verdict of a finished run (re-thresholding or a
  // person's review) and records it in the verdict history; a pass queues
  // the clip for the next stage, anything else drops its later stages.
  void SetVerdict(ClipId clip, const std::string& stage, Verdict verdict,
                  const std::string& reason, const std::string& source);

 private:
  db::Statement& Prepare(const std::string& sql);
  // The first column of the first row of a query, or 0 without rows.
  std::int64_t QueryInt(const std::string& sql);
  void Migrate();
  void QueueNextStage(ClipId clip, const std::string& stage);
  void DropLaterStages(ClipId clip, const std::string& stage);
  int StagePosition(const std::string& stage);

  std::filesystem::path path_;
  std::filesystem::path root_;
  sqlite3* db_ = nullptr;
  double busy_timeout_s_;
  std::map<std::string, std::unique_ptr<db::Statement>> statements_;
  std::vector<std::string> pipeline_cache_;
  int transaction_depth_ = 0;
};

// Seconds since the epoch, the clock of every timestamp in the database.
double Now();

}  // namespace doasido
