// Past one machine: the queue split into shard databases that run anywhere
// (a Slurm array task, another workstation) and are folded back.
//
// A shard is a folder <out>/shard-NNN/ holding doasido.db (same schema and
// pipeline as the parent, its clips with their videos, runs and results)
// and the clips' artifact folders. All clips of one video go to one shard;
// videos are spread over shards by frame count (largest first, each to the
// shard with the fewest frames so far). The parent keeps a row per shard and
// per clip; its own workers leave those clips alone until they come back.
// SQLite files are never shared over a network filesystem: each shard is
// run where it lives (node-local disk) and copied back whole.
#pragma once

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/config.h"
#include "db/database.h"
#include "pipeline/slurm.h"

namespace doasido::pipeline {

struct ShardOptions {
  int shards = 4;
  std::filesystem::path out_dir;  // shard folders go here (created)
  // {stage: parameter hash} of the configuration the shards will run with;
  // a merge refuses runs done with other parameters.
  Json stage_hashes = Json::object();
  // Video path prefixes rewritten in the shards (old -> new).
  std::vector<std::pair<std::string, std::string>> media_map;
};

struct ShardInfo {
  std::string name;
  std::filesystem::path db;  // <out>/shard-NNN/doasido.db
  std::int64_t clips = 0, videos = 0, frames = 0;
};

// Splits the clips with unfinished runs that are in no shard yet. Shards
// that would get no clip are not made. Throws Error("nothing_to_shard") when
// there are none, Error("shard_exists") when a shard folder is in the way.
std::vector<ShardInfo> ShardQueue(Database& db, const ShardOptions& options);

// The rows of shard database `shard_db` merged into `db` (Database::
// MergeShard; a refused shard changes nothing) together with its clips'
// stage folders: copied (never hard links: a re-run of the shard cannot
// change the parent's files) into a staging folder first, committed with
// the rows as a placement journal, then moved into place; a merge killed
// after its commit is finished by the next open of `db`, so readers see
// the old rows and files or the new ones. A clip with a recorded artifact
// file missing in the shard is not merged and is named in
// MergeStats::held_back; the others are. Throws Error("self_merge") when
// `shard_db` is `db`, Error("merge_in_progress") while another merge is
// placing its files. Safe to repeat. ShardQueue copies the other way.
Database::MergeStats MergeShard(Database& db, const std::filesystem::path& shard_db);

// The shard folders' database name.
inline constexpr const char* kShardDbName = "doasido.db";

}  // namespace doasido::pipeline

namespace doasido::pipeline {

// Where one shard stands, for `doasido status`.
struct ShardProgress {
  Database::ShardRow shard;
  bool file_found = false;
  std::int64_t clips_finished = 0;  // every run of the clip done or failed in the shard
  std::int64_t clips_failed = 0;    // of those, with a failed run
  std::int64_t runs_open = 0;       // pending or running in the shard
  std::set<std::string> open_stages;  // stages with a pending or running run there
  // The shard's first task (in group order) that Slurm still lists: its
  // group's index (-1: none listed), state (PENDING, RUNNING, ...) and
  // squeue reason.
  int slurm_group = -1;
  std::string slurm_state;
  std::string slurm_reason;
  bool merged = false;              // merged since its last change
};
// `slurm_states` from SlurmTaskStates (may be empty).
std::vector<ShardProgress> ReadShardProgress(Database& db,
                                             const std::map<std::string, SlurmTask>& slurm_states);

// The array job ids of a shard row, one per stage group, first to last
// (the shards table's slurm_job holds them comma-separated).
std::vector<std::string> ShardJobs(const Database::ShardRow& row);

}  // namespace doasido::pipeline
