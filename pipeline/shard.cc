#include "pipeline/shard.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include <unistd.h>

#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/tree_copy.h"
#include "core/whole_output.h"

namespace doasido::pipeline {
namespace {

struct VideoGroup {
  VideoId video = 0;
  std::int64_t frames = 0;
  std::vector<ClipId> clips;
};

// Largest group first, each to the lightest shard so far (ties: lowest index).
std::vector<std::vector<const VideoGroup*>> Balance(std::vector<VideoGroup>& groups, int shards) {
  std::stable_sort(groups.begin(), groups.end(),
                   [](const VideoGroup& a, const VideoGroup& b) { return a.frames > b.frames; });
  std::vector<std::vector<const VideoGroup*>> out(static_cast<size_t>(shards));
  std::vector<std::int64_t> load(static_cast<size_t>(shards), 0);
  for (const VideoGroup& g : groups) {
    const auto lightest = std::min_element(load.begin(), load.end()) - load.begin();
    out[static_cast<size_t>(lightest)].push_back(&g);
    load[static_cast<size_t>(lightest)] += g.frames;
  }
  return out;
}

namespace fs = std::filesystem;

// Regular files under `dir`, relative path -> size.
std::map<std::string, std::uintmax_t> FilesUnder(const fs::path& dir) {
  std::map<std::string, std::uintmax_t> out;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    if (it->is_regular_file()) out[fs::relative(it->path(), dir).generic_string()] = it->file_size();
  }
  return out;
}

bool SameBytes(const fs::path& a, const fs::path& b) {
  std::ifstream x(a, std::ios::binary), y(b, std::ios::binary);
  return std::equal(std::istreambuf_iterator<char>(x), std::istreambuf_iterator<char>(),
                    std::istreambuf_iterator<char>(y), std::istreambuf_iterator<char>());
}

// Whether two folders hold the same files with the same bytes.
bool SameTree(const fs::path& a, const fs::path& b) {
  const auto files = FilesUnder(a);
  if (files != FilesUnder(b)) return false;
  for (const auto& [rel, size] : files) {
    if (!SameBytes(a / rel, b / rel)) return false;
  }
  return true;
}

// The stage folders of `clip` under an artifact root. Hidden folders (runs
// still writing, staging) are not results.
std::set<std::string> StageFolders(const fs::path& root, ClipId clip) {
  std::set<std::string> out;
  std::error_code ec;
  for (fs::directory_iterator it(root / std::to_string(clip), ec), end; !ec && it != end; it.increment(ec)) {
    const std::string leaf = it->path().filename().string();
    if (!leaf.empty() && leaf[0] != '.' && it->is_directory()) out.insert(leaf);
  }
  return out;
}

// Copies, never links: the two databases never share a file, so a re-run
// of either cannot change the other's.
void CopyFolder(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  CopyTreeAsOurs(from, to, ec);
  if (ec) throw Error("io", "cannot copy artifacts: " + ec.message(), {.file = from.string()});
}

// Copies the shard's stage folders that differ from the parent's into a
// fresh staging folder of the parent's artifact root, and lists the
// parent's stage folders the shard lacks (its rows, which replace the
// parent's, record none). Nothing a reader looks at changes yet.
Database::MergePlacement StageShardFiles(const fs::path& shard_root, const fs::path& root,
                                         const std::vector<ClipId>& clips) {
  char name[48];
  std::snprintf(name, sizeof name, ".merge-%ld-%08x", static_cast<long>(getpid()), std::random_device()());
  Database::MergePlacement p{.staging = name, .pid = static_cast<long>(getpid())};
  try {
    for (ClipId clip : clips) {
      const std::string c = std::to_string(clip);
      const std::set<std::string> theirs = StageFolders(shard_root, clip);
      for (const std::string& stage : theirs) {
        const fs::path mine = root / c / stage;
        if (fs::is_directory(mine) && SameTree(shard_root / c / stage, mine)) continue;
        CopyFolder(shard_root / c / stage, root / name / c / stage);
        p.place.emplace_back(clip, stage);
      }
      for (const std::string& stage : StageFolders(root, clip)) {
        if (!theirs.count(stage)) p.remove.emplace_back(clip, stage);
      }
    }
  } catch (...) {
    std::error_code ec;
    fs::remove_all(root / name, ec);
    throw;
  }
  return p;
}

// A shard is built whole in a temporary sibling of its folder (database
// and artifacts), then moved into place inside the transaction that records
// it here: a kill leaves nothing (or a temporary), the shard recorded with
// its folder, or (between the move and the commit) a folder that
// RemoveKilledShards removes.
void WriteShardFolder(Database& db, const Database::ShardSpec& spec) {
  const fs::path folder = spec.path.parent_path();
  const fs::path temp = TempSibling(folder);
  try {
    fs::create_directories(folder.parent_path());
    MarkTemporary(temp);
    fs::create_directories(temp);
    db.WriteShardDatabase(spec, temp / kShardDbName);
    {
      Database shard(temp / kShardDbName);
      shard.ClaimArtifactRoot();
      for (ClipId c : spec.clips) {
        for (const std::string& stage : StageFolders(db.ArtifactRoot(), c)) {
          CopyFolder(db.ArtifactRoot() / std::to_string(c) / stage,
                     shard.ArtifactRoot() / std::to_string(c) / stage);
        }
      }
    }
    db.RegisterShard(spec, [&] {
      if (std::rename(temp.c_str(), folder.c_str()) != 0) {
        throw Error("io", std::string("cannot move the shard into place: ") + std::strerror(errno),
                    {.file = folder.string()});
      }
    });
    UnmarkTemporary(temp);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(temp, ec);
    UnmarkTemporary(temp);
    throw;
  }
}

// Shard folders under `out_dir` that a killed `shard` moved into place
// without recording them (and temporaries it left): removed, named.
void RemoveKilledShards(Database& db, const fs::path& out_dir) {
  for (const fs::path& p : RemoveAbandonedTemporaries(out_dir)) {
    spdlog::warn("removed {}: left by a killed `doasido shard`", p.string());
  }
  std::error_code ec;
  for (fs::directory_iterator it(out_dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (!db.UnlistedShardOf(it->path() / kShardDbName)) continue;
    std::error_code rm;
    fs::remove_all(it->path(), rm);
    spdlog::warn("removed {}: a shard that a killed `doasido shard` left unrecorded", it->path().string());
  }
}

// Clips of the shard with a recorded artifact file that is missing, each
// named with the file.
std::map<ClipId, std::string> MissingArtifacts(Database& shard) {
  std::map<ClipId, std::string> out;
  std::error_code ec;
  for (const ClipRecord& clip : shard.ListClips()) {
    for (const auto& [stage, rel] : shard.ListArtifacts(clip.id)) {
      const fs::path file = shard.ArtifactRoot() / rel;
      if (fs::exists(file, ec)) continue;
      out[clip.id] = "clip " + std::to_string(clip.id) + ": " + stage + " file " + file.string() +
                     " is missing";
      break;
    }
  }
  return out;
}

}  // namespace

std::vector<ShardInfo> ShardQueue(Database& db, const ShardOptions& options) {
  if (options.shards < 1) {
    throw Error("bad_option", "need at least one shard", {.field = "shards"});
  }
  std::map<VideoId, VideoGroup> by_video;
  for (const auto& c : db.ShardCandidates()) {
    VideoGroup& g = by_video[c.video_id];
    g.video = c.video_id;
    g.frames += c.frames;
    g.clips.push_back(c.clip_id);
  }
  if (by_video.empty()) {
    throw Error("nothing_to_shard",
                "no clip has unfinished work outside a shard (doasido status shows the queue)",
                {.file = db.path().string()});
  }
  std::vector<VideoGroup> groups;
  for (auto& [id, g] : by_video) groups.push_back(std::move(g));
  const auto plan = Balance(groups, options.shards);

  RemoveKilledShards(db, options.out_dir);
  const int existing = static_cast<int>(db.ListShards().size());
  std::vector<ShardInfo> made;
  for (size_t i = 0; i < plan.size(); ++i) {
    if (plan[i].empty()) continue;
    char name[32];
    std::snprintf(name, sizeof name, "shard-%03d", existing + static_cast<int>(made.size()));
    ShardInfo info{name, options.out_dir / name / kShardDbName};
    Database::ShardSpec spec{.name = name, .path = info.db, .stage_hashes = options.stage_hashes,
                             .media_map = options.media_map};
    for (const VideoGroup* g : plan[i]) {
      spec.clips.insert(spec.clips.end(), g->clips.begin(), g->clips.end());
      spec.frames += g->frames;
    }
    std::sort(spec.clips.begin(), spec.clips.end());
    info.clips = static_cast<std::int64_t>(spec.clips.size());
    info.videos = static_cast<std::int64_t>(plan[i].size());
    info.frames = spec.frames;
    WriteShardFolder(db, spec);
    made.push_back(info);
  }
  return made;
}

Database::MergeStats MergeShard(Database& db, const std::filesystem::path& shard_db) {
  std::error_code ec;
  if (fs::equivalent(shard_db, db.path(), ec)) {
    throw Error("self_merge", "this is the database being merged into, not a shard of it",
                {.file = fs::absolute(shard_db).string()});
  }
  if (!fs::is_regular_file(shard_db, ec)) {
    throw Error("not_a_shard", "no such shard database", {.file = fs::absolute(shard_db).string()});
  }
  db.ClaimArtifactRoot();
  if (db.GetMeta(Database::kPlacementKey)) {
    throw Error("merge_in_progress", "another merge into this database is placing its files; run again when it ends",
                {.file = db.path().string()});
  }
  for (const fs::path& p : db.RemoveAbandonedStaging()) {
    spdlog::info("removed {} (left by a merge killed before its commit)", p.string());
  }
  // A clip whose recorded file is missing stays unmerged, named.
  std::map<ClipId, std::string> missing;
  fs::path shard_root;
  std::vector<ClipId> clips;
  {
    Database shard(shard_db, Database::OpenMode::kExisting);
    missing = MissingArtifacts(shard);
    shard_root = shard.ArtifactRoot();
    for (const ClipRecord& clip : shard.ListClips()) {
      if (!missing.count(clip.id)) clips.push_back(clip.id);
    }
  }
  std::set<ClipId> hold_back;
  for (const auto& [clip, why] : missing) hold_back.insert(clip);
  // Files first into staging, then the rows and the placement journal in
  // one transaction, then the files into place: a kill at any moment
  // leaves the old rows and files, or the new rows with a journal that the
  // next open of this database finishes (Database::FinishPlacement).
  const Database::MergePlacement placement = StageShardFiles(shard_root, db.ArtifactRoot(), clips);
  const bool moves = !placement.place.empty() || !placement.remove.empty();
  // Readers wait from before the commit until the folders are in place.
  const Database::ArtifactLock placing = db.LockForPlacement();
  Database::MergeStats stats;
  try {
    stats = db.MergeShard(shard_db, hold_back, moves ? Database::PlacementJson(placement) : "");
  } catch (...) {
    fs::remove_all(db.ArtifactRoot() / placement.staging, ec);
    throw;
  }
  // No clip merged: a shard merged before handed its clips back, and their
  // files are this database's now (they may be newer than the shard's).
  if (db.GetMeta(Database::kPlacementKey)) {
    db.FinishPlacement(/*own=*/true);
  } else {
    fs::remove_all(db.ArtifactRoot() / placement.staging, ec);
  }
  for (const auto& [clip, why] : missing) stats.held_back.push_back(why);
  return stats;
}

}  // namespace doasido::pipeline

namespace doasido::pipeline {

std::vector<std::string> ShardJobs(const Database::ShardRow& row) {
  std::vector<std::string> jobs;
  std::istringstream parts(row.slurm_job);
  for (std::string job; std::getline(parts, job, ',');) jobs.push_back(job);
  return jobs;
}

std::vector<ShardProgress> ReadShardProgress(
    Database& db, const std::map<std::string, SlurmTask>& slurm_states) {
  std::vector<ShardProgress> out;
  for (const auto& row : db.ListShards()) {
    ShardProgress p{.shard = row};
    const auto jobs = ShardJobs(row);
    for (size_t g = 0; g < jobs.size() && row.slurm_task && p.slurm_group < 0; ++g) {
      const auto it = slurm_states.find(jobs[g] + "_" + std::to_string(*row.slurm_task));
      if (it == slurm_states.end()) continue;
      p.slurm_group = static_cast<int>(g);
      p.slurm_state = it->second.state;
      p.slurm_reason = it->second.reason;
    }
    p.file_found = std::filesystem::is_regular_file(row.path);
    if (p.file_found) {
      Database shard(row.path);
      std::map<ClipId, std::pair<bool, bool>> clips;  // (open, failed)
      for (const auto& r : shard.ReportRuns()) {
        auto& [open, failed] = clips[r.clip_id];
        open = open || r.state == "pending" || r.state == "running";
        failed = failed || r.state == "failed";
        if (r.state == "pending" || r.state == "running") {
          ++p.runs_open;
          p.open_stages.insert(r.stage);
        }
      }
      for (const auto& [id, c] : clips) {
        if (!c.first) ++p.clips_finished;
        if (!c.first && c.second) ++p.clips_failed;
      }
    }
    p.merged = row.merged_at.has_value() && p.runs_open == 0;
    out.push_back(p);
  }
  return out;
}

}  // namespace doasido::pipeline
