#include "pipeline/shard.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

#include "core/error.h"

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

// Copies one stage folder into place: into a hidden staging sibling first,
// then swapped in (renameat2 RENAME_EXCHANGE), so the folder is the old one
// or the complete new one. Copies, never links: the two databases never
// share a file, so a re-run of either cannot change the other's.
void PlaceFolder(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  if (fs::is_directory(to, ec) && SameTree(from, to)) return;
  const fs::path staging = to.parent_path() / ("." + to.filename().string() + ".merge-" +
                                               std::to_string(getpid()));
  fs::remove_all(staging, ec);
  fs::create_directories(to.parent_path(), ec);
  fs::copy(from, staging, fs::copy_options::recursive, ec);
  if (ec) {
    fs::remove_all(staging, ec);
    throw Error("io", "cannot copy artifacts: " + ec.message(), {.file = from.string()});
  }
  const bool replace = fs::exists(to, ec);
  const int rc = replace ? renameat2(AT_FDCWD, staging.c_str(), AT_FDCWD, to.c_str(), RENAME_EXCHANGE)
                         : std::rename(staging.c_str(), to.c_str());
  if (rc != 0) {
    const int err = errno;
    fs::remove_all(staging, ec);
    throw Error("io", std::string("cannot place artifacts: ") + std::strerror(err), {.file = to.string()});
  }
  fs::remove_all(staging, ec);  // the replaced folder, after an exchange
}

// Copies the stage folders of `clip` from one artifact root to another.
// Hidden folders (runs still writing, staging) are not results and stay.
// `mirror`: a stage folder the source lacks is removed at the destination
// too (the source's rows, which replace the destination's, record none).
void CopyClipArtifacts(const fs::path& from_root, const fs::path& to_root, ClipId clip,
                       bool mirror) {
  const fs::path from = from_root / std::to_string(clip);
  const fs::path to = to_root / std::to_string(clip);
  std::error_code ec;
  std::set<std::string> stages;
  for (const auto& entry : fs::directory_iterator(from, ec)) {
    const std::string leaf = entry.path().filename().string();
    if (leaf.empty() || leaf[0] == '.' || !entry.is_directory()) continue;
    stages.insert(leaf);
    PlaceFolder(entry.path(), to / leaf);
  }
  if (!mirror) return;
  for (const auto& entry : fs::directory_iterator(to, ec)) {
    const std::string leaf = entry.path().filename().string();
    if (leaf.empty() || leaf[0] == '.' || !entry.is_directory() || stages.count(leaf)) continue;
    fs::remove_all(entry.path(), ec);
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
    std::filesystem::create_directories(info.db.parent_path());
    db.ExportShard(spec);
    Database shard(info.db);
    shard.ClaimArtifactRoot();
    for (ClipId c : spec.clips) CopyClipArtifacts(db.ArtifactRoot(), shard.ArtifactRoot(), c, false);
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
  // A clip whose recorded file is missing stays unmerged, named; the rows
  // go first (a refused shard must not leave files here), then the files.
  std::map<ClipId, std::string> missing;
  fs::path shard_root;
  {
    Database shard(shard_db, Database::OpenMode::kExisting);
    missing = MissingArtifacts(shard);
    shard_root = shard.ArtifactRoot();
  }
  std::set<ClipId> hold_back;
  for (const auto& [clip, why] : missing) hold_back.insert(clip);
  Database::MergeStats stats = db.MergeShard(shard_db, hold_back);
  for (const auto& [clip, why] : missing) stats.held_back.push_back(why);
  db.ClaimArtifactRoot();
  // A shard merged before handed its clips back: their files are this
  // database's now, and may be newer than the shard's.
  if (stats.clips == 0) return stats;
  Database shard(shard_db, Database::OpenMode::kExisting);
  for (const ClipRecord& clip : shard.ListClips()) {
    if (hold_back.count(clip.id)) continue;
    CopyClipArtifacts(shard_root, db.ArtifactRoot(), clip.id, true);
  }
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
