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
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "core/clock.h"  // Now(), the clock of every timestamp here
#include "core/output_path.h"
#include "core/records.h"
#include "db/stage_records.h"

struct sqlite3;

namespace doasido {

namespace db {
class Statement;
}

enum class RunState { kPending, kRunning, kDone, kFailed };
const char* ToString(RunState s);
// Inverse of ToString; throws Error("database") for any other text.
RunState ParseRunState(std::string_view text);
// A state equals its stored name ("pending", "running", "done", "failed").
inline bool operator==(RunState state, std::string_view text) { return text == ToString(state); }

// The verdict-history source of a person's decision (the others are "stage"
// and "rethreshold").
inline constexpr const char* kHumanVerdictSource = "human";

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
  RunState state = RunState::kPending;
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
  std::int64_t sharded = 0;  // unfinished runs of clips handed to shards (not counted above)
};

class Database {
 public:
  // Opens or creates the file and upgrades its schema. Throws Error
  // ("database") naming the file when it cannot, or when the schema is
  // newer than this program understands.
  // kCreate makes the file when it is missing (init, ingest, run and the
  // worker); kExisting refuses a missing file with Error("no_database")
  // (the commands that only look: status, queue, report, review). Either
  // refuses another program's SQLite file with Error("foreign_database")
  // without writing to it: doasido marks its files with SQLite's
  // application_id (kApplicationId).
  enum class OpenMode { kCreate, kExisting };
  static constexpr int kApplicationId = 0x646f6173;  // "doas"
  explicit Database(const std::filesystem::path& path, double busy_timeout_s = 60.0,
                    OpenMode mode = OpenMode::kCreate);
  ~Database();
  Database(const std::filesystem::path& path, OpenMode mode) : Database(path, 60.0, mode) {}
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // True when the file (or its folder) cannot be written: it was opened
  // read-only, and any write throws Error(kReadOnly) naming it.
  bool read_only() const { return read_only_; }
  // The folder relative paths are resolved against.
  const std::filesystem::path& root() const { return root_; }
  int SchemaVersion();
  static int LatestSchemaVersion();

  // ---- Artifacts (db/database_artifacts.cc) ---------------------------------
  // The folder of this database's artifacts, decided, claimed and recorded
  // (meta key kArtifactRootKey, relative to the database folder) when it is
  // created: <database folder>/artifacts for the first doasido database in
  // it, else <database folder>/<file stem>.artifacts (one that has a root
  // keeps it). The folder holds kArtifactOwnerFile with the database's uuid;
  // opening a database whose recorded folder belongs to another one throws
  // Error("foreign_artifacts") naming both. Stored artifact paths are
  // relative to it.
  static constexpr const char* kArtifactRootKey = "artifact_root";
  static constexpr const char* kArtifactOwnerFile = kArtifactRootMarker;
  const std::filesystem::path& ArtifactRoot() const { return artifact_root_; }
  // Writes the owner file (creating the folder) if missing; before the first artifact.
  void ClaimArtifactRoot();
  // <artifact root>/<clip>/<stage>/, the published output of the clip's
  // recorded run of `stage` (not created). The ONE place that computes it.
  std::filesystem::path ArtifactDir(ClipId clip, const std::string& stage) const;
  // The fresh folder a claimed run writes into, a hidden sibling of its
  // ArtifactDir (<root>/<clip>/.<stage>.run-<run id>-<attempt>), published
  // by renaming when the run completes (PublishArtifacts).
  std::filesystem::path ArtifactWorkDir(const Claim& claim) const;
  // The output of the run the database records for (clip, stage), for every
  // reader of artifacts (deploy plan, dataset create, /verify, the next
  // stage): the run must be done with verdict pass (a flag a person accepted
  // is a pass), or flag too when `allow_flag`, and its folder must exist.
  // Otherwise nullopt, with *why (when given) naming the run and what it is.
  struct RunOutput {
    std::int64_t run_id = 0;
    ClipId clip_id = 0;
    std::string stage;
    std::filesystem::path dir;  // ArtifactDir(clip, stage)
    std::string verdict, reason, param_hash;
  };
  // Renames the claim's work folder into place as its ArtifactDir; the
  // folder it replaces is moved aside (removed by RemoveArtifactLeftovers).
  // An empty work folder is removed and nothing is published (the previous
  // folder is then removed too: it is not this run's). Call before
  // Complete: a process killed in between leaves the run `running`, whose
  // folder no reader takes. Throws Error("io") naming the folder.
  void PublishArtifacts(const Claim& claim);
  // Removes what killed or replaced runs of (clip, stage) left: work
  // folders and folders moved aside.
  void RemoveArtifactLeftovers(ClipId clip, const std::string& stage);
  std::optional<RunOutput> RecordedOutput(ClipId clip, const std::string& stage, bool allow_flag,
                                          std::string* why = nullptr);
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
  // `flag_continues`: stages where a flag does not stop the clip: it goes on
  // to the next stage (the filters: a person then sees every filter's
  // verdict), and waits for a person only before the first stage that is
  // not in this set's reach (see MoveOn).
  void SetPipeline(const std::vector<std::string>& stages,
                   const std::set<std::string>& flag_continues = {});
  std::vector<std::string> Pipeline();
  std::set<std::string> FlagContinuing();

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
  // A run waits while an earlier stage of its clip is not done (a changed
  // upstream run queues its downstream runs before it has run again).
  // A run whose attempts reached `max_attempts` is failed instead of handed
  // out. Returns nullopt when nothing is claimable right now.
  std::optional<Claim> ClaimNext(const std::string& worker, const std::vector<std::string>& stages,
                                 double lease_s, int max_attempts);
  // Who holds a lease: "<host>:<command pid>/<worker pid>" (the command a
  // person started, and the process that runs the stage; the same for a
  // command that runs stages itself, as `rethreshold`). The ONE place that
  // writes the form; ExpireDeadLeases reads it.
  static std::string LeaseOwner(long command_pid, long worker_pid);
  struct Lease {
    std::int64_t run_id = 0;
    ClipId clip_id = 0;
    std::string stage, owner;
    double expires = 0;  // seconds since the epoch
  };
  // Runs leased by a process of this machine that is gone (its worker pid
  // runs no more): their leases end now, so the next ClaimNext takes them
  // over at once instead of after the lease. Returns them.
  std::vector<Lease> ExpireDeadLeases();
  // Running runs of `stages` (all when empty) whose lease still holds.
  std::vector<Lease> LiveLeases(const std::vector<std::string>& stages);
  // Extends the lease; false when the worker no longer holds it.
  bool Heartbeat(std::int64_t run_id, const std::string& worker, double lease_s);
  // Records the result and marks the run done, with the upstream runs it
  // consumed (stage_runs.inputs, see UpstreamInputs); later runs of the clip
  // are queued again (they consumed the old result), and the clip is queued
  // for the next stage when the verdict is pass. Returns false (and changes nothing)
  // when `worker` no longer holds the lease: the run was reclaimed and its
  // result belongs to whoever holds it now.
  bool Complete(const Claim& claim, const std::string& worker, const std::string& param_hash,
                const StageResult& result, double duration_s);
  // Records a failed attempt: back to pending while attempts < max_attempts,
  // else failed (and the clip's later runs dropped). Either way the run has
  // no verdict, and the error text is kept, bounded to kMaxStoredTextBytes
  // (core/bounded_text.h, its tail). Returns false (nothing recorded) when
  // `worker` no longer holds the run.
  bool Fail(const Claim& claim, const std::string& worker, const std::string& error,
            int max_attempts);
  // Done runs of `stage` whose parameters differ from `param_hash` go back
  // to pending without a verdict (new parameters: re-run; same: no-op), and
  // with them every later run of those clips (RequeueDownstream); their
  // number goes to `downstream` when given. Returns the runs of `stage`.
  std::int64_t InvalidateOtherParams(const std::string& stage, const std::string& param_hash,
                                     std::int64_t* downstream = nullptr);
  // The one mechanism by which a changed run reaches what follows it: every
  // later run of `clip` goes back to pending without a verdict, lease or
  // error, marked as queued again because of `stage` (requeued_by).
  // Returns how many runs were not already waiting for that reason.
  std::int64_t RequeueDownstream(ClipId clip, const std::string& stage);
  // The done runs before `stage` in `clip`'s pipeline, as a run records what
  // it consumed: [{stage, param_hash, finished_at, artifacts: [..]}] (a run
  // is its stage and finish time: row ids change when a shard is merged).
  Json UpstreamInputs(ClipId clip, const std::string& stage);
  // Runs of `stages` (all when empty) a worker could claim now or that run:
  // what `--until-empty` waits for.
  std::int64_t CountOpen(const std::vector<std::string>& stages);
  // Pending runs queued again because an earlier run changed, by that stage.
  std::map<std::string, std::int64_t> CountRequeued();
  // failed -> pending with attempts reset. Empty stage: all stages.
  std::int64_t Retry(const std::string& stage, std::optional<ClipId> clip);
  // Any state -> pending with attempts reset, and the clip's later stages
  // dropped. Empty stage is not allowed.
  std::int64_t Reset(const std::string& stage, std::optional<ClipId> clip);
  // Runs by state; of `stages` only when given (a worker limited to some
  // stages is done when they are).
  QueueSummary Summary(const std::vector<std::string>& stages = {});
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
  // Replaces a finished run's result with one re-derived from its stored
  // measurements under new parameters (re-thresholding; nothing is decoded):
  // measurements, parameter hash and verdict are replaced and the verdict
  // history gets a "rethreshold" row. When `changed`, the clip's later stages
  // are dropped and, on pass, the next stage is queued, so later stages judge
  // the new result. Returns false, changing nothing, when the run is not done
  // or its current verdict was given by a person (source "human").
  // `requeued` (when given) gets the later runs of the clip left waiting
  // to run again on the new result (RequeueDownstream, then MoveOn).
  bool StoreRedecision(ClipId clip, const std::string& stage, const std::string& param_hash,
                       const StageResult& result, bool changed, std::int64_t* requeued = nullptr);
  // The clip's stored measurements, by stage, whose JSON value at
  // `json_path` (SQLite's json_extract, e.g. "$.not_measured.stage")
  // equals `value`.
  std::map<std::string, Json> MeasurementsWhere(ClipId clip, const std::string& json_path,
                                                const std::string& value);

  // ---- Reports --------------------------------------------------------------
  // Bulk reads for `doasido report` (db/database_reports.cc). Read-only.

  // One stage run as the playbook report counts it.
  struct ReportRun {
    ClipId clip_id = 0;
    std::string stage;
    int position = 0;
    std::string state;    // pending, running, done, failed
    std::string verdict;  // empty until decided
    std::string reason;
    std::string error;
    int attempts = 0;
    std::optional<double> duration_s;  // set once done
    // Source of the latest verdict history row ('stage', 'rethreshold',
    // 'human'); empty without one.
    std::string verdict_source;
    std::string param_hash;  // empty until done
    std::int64_t run_id = 0;
    std::optional<double> finished_at;  // set once done
    Json inputs;                        // UpstreamInputs when it finished; null before
    std::string requeued_by;            // the upstream stage that queued it again
  };
  // Every stage run, ordered by clip id and pipeline position.
  std::vector<ReportRun> ReportRuns();
  // Every clip as GetClip reads it, ordered by id; `videos` (when not null)
  // gets each clip's absolute video path (or URL) keyed by clip id.
  std::vector<ClipRecord> ListClips(std::map<ClipId, std::string>* videos = nullptr);
  // Calls fn(clip, summary) for each clip whose run of `stage` is done, in
  // clip order, where summary is the measurements' "summary" member (null
  // when absent). Only that member is parsed: signals can be large.
  void ForEachSummary(const std::string& stage,
                      const std::function<void(ClipId, const Json&)>& fn);
  struct EventCount {
    std::string stage;
    std::string kind;
    std::string worker;
    std::int64_t count = 0;
  };
  // Events grouped by stage, kind and worker.
  std::vector<EventCount> CountEvents();
  struct EventRow {
    std::int64_t id = 0;
    double at = 0;
    std::optional<ClipId> clip_id;
    std::string stage, kind, worker, detail;
  };
  // Events of one of `kinds`, oldest first, at most `limit` (0: all).
  std::vector<EventRow> ListEvents(const std::vector<std::string>& kinds, int limit);

  // ---- Review ---------------------------------------------------------------
  // (db/database_review.cc) Flagged clips waiting for a person, their
  // decisions, and the tables of preference studies (schema v2).
  struct FlaggedRun {
    ClipId clip_id = 0;
    std::string external_id;
    std::string stage;
    std::string reason;
  };
  struct ReviewRow {
    std::int64_t id = 0;
    ClipId clip_id = 0;
    std::string stage, reviewer, decision, reason;  // decision: accept | reject
    double created_at = 0;
    // What a verification was given for (schema v7): the SHA-256 of the
    // trajectory file shown and the run's parameter hash; empty for reviews.
    std::string artifact_sha256, param_hash;
  };
  struct VerdictRow {
    std::string verdict, reason, source;  // source: stage | rethreshold | human
    double created_at = 0;
  };
  struct StudyRecord {
    std::int64_t id = 0;
    std::string name;
    int raters_per_item = 3;
    std::int64_t seed = 0;
    std::string items_file;
    double created_at = 0;
  };
  struct StudyItemRecord {
    std::int64_t id = 0;  // row id; item_id is the name from the items file
    std::string item_id;
    std::string source_video, a_video, b_video;  // absolute paths
    std::string a_label, b_label;
  };
  struct StudyTrialRecord {
    std::int64_t id = 0;
    std::int64_t item = 0;  // StudyItemRecord::id
    std::string rater;
    bool left_is_a = true;
    std::string side;    // left | right | tie; empty until answered
    std::string choice;  // a | b | tie; empty until answered
    double shown_at = 0;
    std::optional<double> answered_at;
  };

  // Done runs whose verdict is flag, in clip then pipeline order, of clips
  // that wait for a person: every stage they went on to has finished and
  // none rejected them.
  std::vector<FlaggedRun> ListFlagged();
  std::int64_t CountFlagged();
  // A person's decision on a flagged run, in one transaction: a `reviews`
  // row, the human verdict (accept -> pass, which queues the next stage;
  // reject -> reject) with its history, and a "review" event. Throws
  // Error("not_flagged") and writes nothing when the run is not flagged.
  void RecordReview(ClipId clip, const std::string& stage, const std::string& reviewer,
                    bool accept, const std::string& reason);
  std::vector<ReviewRow> ListReviews();
  // Verdict history of one run, oldest first.
  std::vector<VerdictRow> VerdictHistory(ClipId clip, const std::string& stage);

  // Creates a study with its items (paths stored relative to the database
  // folder when inside it). Throws Error("study_exists") for a taken name.
  std::int64_t CreateStudy(const StudyRecord& study, const std::vector<StudyItemRecord>& items);
  std::optional<StudyRecord> GetStudy(const std::string& name);
  std::vector<StudyItemRecord> GetStudyItems(std::int64_t study_id);
  std::optional<StudyItemRecord> GetStudyItem(std::int64_t item);  // by row id
  // Every trial of the study's items, in creation order.
  std::vector<StudyTrialRecord> GetStudyTrials(std::int64_t study_id);
  std::optional<StudyTrialRecord> GetStudyTrial(std::int64_t trial_id);
  // Opens a trial of `item` for `rater`; throws Error("trial_exists") when
  // the rater already has one for this item.
  std::int64_t InsertStudyTrial(std::int64_t item, const std::string& rater, bool left_is_a);
  // Records the rater's side (left | right | tie) and the choice it maps to.
  // False (nothing written) when the trial is already answered, belongs to
  // another rater, or its item already has all its ratings.
  bool AnswerStudyTrial(std::int64_t trial_id, const std::string& rater, const std::string& side);

  // ---- Downloads ------------------------------------------------------------
  // (db/database_downloads.cc, schema v4) Videos listed by URL and fetched
  // into the database's media folder by the download stage.

  // The measurements member by which a stage hands over the local file of
  // the clip's video: {"path": absolute path, "size_bytes": n, "sha256": hex}.
  // Complete() records it on the clip's videos row (RecordVideoFile); from
  // then on GetVideo, and so every later stage's ClipContext, gives the local
  // file instead of the URL.
  static constexpr const char* kVideoFileKey = "video_file";
  struct VideoFile {
    std::string url;         // the video as listed
    std::string local_path;  // absolute
    std::int64_t size_bytes = 0;
    std::string sha256;
    double downloaded_at = 0;
  };
  // Records `file` (a kVideoFileKey member) on the videos row of `clip`.
  // Throws Error("bad_measurements") when it lacks path, size or checksum.
  void RecordVideoFile(ClipId clip, const Json& file);
  // The downloaded file of a video, or nullopt when it has none.
  std::optional<VideoFile> GetVideoFile(VideoId video);
  // Videos with a downloaded file.
  std::int64_t CountDownloadedVideos();
  // ---- Shards ---------------------------------------------------------------
  // (db/database_shards.cc) Splitting the queue into self-contained shard
  // databases and folding their results back (doasido shard, merge, slurm).
  // Clips keep their ids in a shard, so a clip is the same row everywhere.

  // This database's identity (created with the schema) and free key/values.
  std::string Uuid();
  std::optional<std::string> GetMeta(const std::string& key);
  void SetMeta(const std::string& key, const std::string& value);

  struct ShardCandidate {
    ClipId clip_id = 0;
    VideoId video_id = 0;
    std::int64_t frames = 1;  // span length when known, else the video's, else 1
  };
  // Clips with an unfinished run (pending, running or failed) that are not
  // in a shard yet, in id order.
  std::vector<ShardCandidate> ShardCandidates();
  struct ShardSpec {
    std::string name;                  // shard-000
    std::filesystem::path path;        // the shard database; must not exist
    Json stage_hashes;                 // {stage: parameter hash} the shard runs with
    std::vector<ClipId> clips;
    std::int64_t frames = 0;
    // Video path prefixes rewritten in the shard (old -> new), for nodes
    // that mount the media elsewhere; other paths are made absolute.
    std::vector<std::pair<std::string, std::string>> media_map;
  };
  // Creates the shard database at `file`: this database's pipeline, the
  // clips with their videos, runs (running ones pending again),
  // measurements, verdicts, reviews, artifact rows and detections, and the
  // shard's parent, name and stage hashes in its meta, committed in the
  // shard's file only. `file` is where it is written (a temporary folder
  // that becomes spec.path's), spec.path where it will live. Artifact files
  // are the caller's to copy. Throws Error("shard_exists") for a taken path,
  // Error("already_sharded") for a clip that is in a shard.
  void WriteShardDatabase(const ShardSpec& spec, const std::filesystem::path& file);
  // Records the shard and its clips here, which takes them out of this
  // database's queue, in one transaction with `before_commit` run inside
  // it (ShardQueue moves the shard's folder into place there): a kill
  // leaves no row, the rows with their folder, or a folder this database
  // does not list (UnlistedShardOf).
  void RegisterShard(const ShardSpec& spec, const std::function<void()>& before_commit = {});
  // Whether `shard_db` is a shard of this database that it does not list:
  // what a `shard` killed after moving a folder into place leaves.
  bool UnlistedShardOf(const std::filesystem::path& shard_db);

  struct ShardRow {
    std::int64_t id = 0;
    std::string name;
    std::filesystem::path path;
    std::string config_hash;
    std::int64_t clips = 0, frames = 0;
    double created_at = 0;
    std::optional<double> merged_at;
    std::string slurm_job;
    std::optional<std::int64_t> slurm_task;
  };
  std::vector<ShardRow> ListShards();
  void SetShardJob(const std::string& name, const std::string& job, std::int64_t task);

  struct MergeStats {
    std::string shard;
    std::int64_t clips = 0;          // clips of the shard
    std::int64_t finished_runs = 0;  // done or failed in the shard
    std::int64_t open_runs = 0;      // still pending or running there
    std::int64_t changed_clips = 0;  // clips whose rows changed here
    std::int64_t events = 0;         // new events folded in
    std::int64_t handed_back = 0;    // clips the parent owns again (shard finished)
    // Clips left unmerged because a file their rows record is missing,
    // each "clip N: <file>" (pipeline::MergeShard fills it in).
    std::vector<std::string> held_back;
  };
  // The shard's meta key naming the database it was merged into.
  static constexpr const char* kMergedIntoKey = "merged_into";
  // Throws Error("merged_shard") naming the parent when this database is a
  // shard already merged back (its clips are the parent's again).
  void RefuseMergedShard();
  // Folds a shard's results into this database: for each of its clips the
  // runs, measurements, verdicts, reviews, artifact rows and detections here
  // become the shard's (rows already equal are left alone, so merging twice
  // changes nothing), and its new events are appended. Unfinished runs stay
  // pending here and remain the shard's to finish; a shard with none left
  // hands its clips back (no longer in shard_clips) and is marked merged
  // (kMergedIntoKey in its meta), so it refuses further runs. Throws
  // Error("not_a_shard"), Error("foreign_shard") for a shard of another
  // database or one this database does not list, Error("pipeline_mismatch"),
  // and Error("config_mismatch") when a run was done with parameters other
  // than the shard was made for; nothing is written then.
  // `hold_back`: clips of the shard whose rows stay as they are here.
  // Throws Error("self_merge") at once when `shard` is this database.
  // `placement`: the journal of stage folders the merge staged (see
  // MergePlacement), recorded in the same transaction as the rows.
  MergeStats MergeShard(const std::filesystem::path& shard, const std::set<ClipId>& hold_back = {},
                        const std::string& placement = "");

  // ---- Placing merged files (db/artifact_placement.cc) ----------------------
  // A merge copies a shard's stage folders into a staging folder of this
  // artifact root first (nothing a reader looks at changes), commits its
  // rows together with this journal (meta kPlacementKey), then moves the
  // staged folders into place and clears the journal. A merge killed after
  // its commit is finished by the next open of this database, so the rows
  // and files a reader sees belong together: the old ones or the new ones.
  struct MergePlacement {
    std::string staging;  // folder under the artifact root, ".merge-<pid>-<hex>"
    long pid = 0;         // the merging process (its journal is left to it)
    std::vector<std::pair<ClipId, std::string>> place;   // staging/<clip>/<stage> -> <clip>/<stage>
    std::vector<std::pair<ClipId, std::string>> remove;  // <clip>/<stage> the shard does not have
  };
  static constexpr const char* kPlacementKey = "pending_placement";
  static std::string PlacementJson(const MergePlacement& placement);
  // Moves a committed merge's staged folders into place and clears the
  // journal; each step may be repeated, so a kill during it is finished by
  // the next call. `own`: the caller is the merging process; otherwise a
  // journal whose process still runs is left to it. Returns the folders
  // placed and removed.
  std::int64_t FinishPlacement(bool own = false);
  // Removes staging folders of merges killed before their commit (their
  // process is gone and no journal names them); returns them.
  std::vector<std::filesystem::path> RemoveAbandonedStaging();
  // Readers never see a merge half placed (db/artifact_lock.cc): a merge
  // holds the artifact root's placement lock (an flock on
  // kPlacementLockFile) exclusively from before its rows commit until its
  // folders are placed; a reader of artifacts (deploy plan, dataset create)
  // holds it shared while it reads rows and files, so it sees the rows and
  // folders of before the merge or of after it. A holder that dies releases
  // it; a journal found under the shared lock is a dead merge's and is
  // finished first. Each says on stderr when it waits. No lock (and no
  // wait) on a read-only artifact root: nothing can merge into it.
  static constexpr const char* kPlacementLockFile = ".doasido-placement.lock";
  class ArtifactLock {
   public:
    explicit ArtifactLock(int fd = -1) : fd_(fd) {}
    ArtifactLock(ArtifactLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
    ArtifactLock& operator=(ArtifactLock&&) = delete;
    ~ArtifactLock();

   private:
    int fd_;
  };
  ArtifactLock LockForReading();
  ArtifactLock LockForPlacement();
  // The artifact rows of `clip` as stored: (stage, path relative to the
  // artifact root).
  std::vector<std::pair<std::string, std::string>> ListArtifacts(ClipId clip);
  // Every running run back to pending with its lease cleared (attempts
  // kept), logged as "release" events; returns how many. Only for a
  // database no live worker holds, e.g. a shard whose task was killed: its
  // leases would otherwise block the next task until they expire.
  std::int64_t ReleaseLeases();

  // ---- Trajectory verification ----------------------------------------------
  // (db/database_verify.cc) Robot trajectories waiting for a person to
  // verify them in the review app (docs/review.md). "Verified" is the
  // trajectory stage's verdict pass set by a person (source "human"), which
  // `dataset create --select verified` selects.
  struct TrajectoryRun {
    ClipId clip_id = 0;
    std::string external_id;
    std::string stage;
    std::string verdict;  // pass | flag
    std::string reason;
  };
  // Done runs of `stages` with verdict pass or flag whose latest verdict was
  // not set by a person, in clip order.
  std::vector<TrajectoryRun> ListTrajectoriesToVerify(const std::vector<std::string>& stages);
  // A person's verification, in one transaction: a `reviews` row, the human
  // verdict (accept -> pass with reason "", reject -> reject with `reason`)
  // and a "review" event. Throws Error("not_verifiable") and writes nothing
  // unless the run is done with verdict pass or flag.
  // The decision binds to the trajectory shown: `trajectory_sha256` (its
  // file's SHA-256) and the run's parameter hash are recorded with it, and
  // only a trajectory with that hash counts as verified by it.
  void RecordVerification(ClipId clip, const std::string& stage, const std::string& reviewer,
                          bool accept, const std::string& reason,
                          const std::string& trajectory_sha256);

 private:
  db::Statement& Prepare(const std::string& sql);
  void WriteShard(const ShardSpec& spec, const std::filesystem::path& file);  // WriteShardDatabase's writes
  // The parts of Complete(), inside its transaction at its time `now`.
  void RecordStageResult(const Claim& claim, const std::string& param_hash,
                         const StageResult& result, double now);
  void ReplaceArtifactRows(const Claim& claim, const StageResult& result, double now);
  void RecordVideoInfo(ClipId clip, const VideoInfo& video, double now);
  // The writes both review and verification make once their check passed:
  // the `reviews` row, the human verdict with `verdict_reason` and a
  // "review" event with `event_detail`.
  void RecordHumanDecision(ClipId clip, const std::string& stage, const std::string& reviewer,
                           bool accept, const std::string& reason,
                           const std::string& verdict_reason, const std::string& event_detail);
  // The first column of the first row of a query, or 0 without rows.
  std::int64_t QueryInt(const std::string& sql);
  void Migrate();
  // Throws Error("foreign_database") unless the file is empty, marked as
  // ours, or a doasido database from before the mark (then marks it).
  void RefuseForeign();
  void QueueNextStage(ClipId clip, const std::string& stage);
  void DropLaterStages(ClipId clip, const std::string& stage);
  // Moves a clip on after `stage` gave `verdict`: a pass, or a flag where
  // flags continue, queues the next stage, except that a clip with a flag at
  // or before `stage` waits for a person before a stage past the flags'
  // reach; a reject, or a flag that stops, drops the later runs.
  void MoveOn(ClipId clip, const std::string& stage, Verdict verdict);
  // After a person's pass: when no flag or reject of the clip is left, the
  // clip goes on from its furthest finished stage.
  void Release(ClipId clip);
  int StagePosition(const std::string& stage);

  // Artifacts (db/database_artifacts.cc): picks and checks artifact_root_.
  void OpenArtifactRoot();
  // Drops the artifact rows and published folders of `clip`'s runs of
  // `stages` (a run that is no longer the recorded result).
  void DiscardArtifacts(ClipId clip, const std::vector<std::string>& stages);
  // The stages after `stage` in the pipeline.
  std::vector<std::string> StagesAfter(const std::string& stage);

  std::filesystem::path path_;
  std::filesystem::path root_;
  std::filesystem::path artifact_root_;
  bool read_only_ = false;  // opened read-only: nobody may write the file (see the constructor)
  sqlite3* db_ = nullptr;
  double busy_timeout_s_;
  std::map<std::string, std::unique_ptr<db::Statement>> statements_;
  std::vector<std::string> pipeline_cache_;
  std::set<std::string> flag_continues_cache_;
  int transaction_depth_ = 0;
};

}  // namespace doasido
