#include "pipeline/shard.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <sstream>

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

// How a clip's artifact folder travels. A shard gets copies (it writes its
// own results beside them); results come home as hard links, which cost no
// space or time, and as copies where the two roots are on different file
// systems (or the file system has no links). A file already linked to its
// source is left alone, so merging twice changes nothing.
enum class Transfer { kCopy, kLink };

void PlaceFile(const std::filesystem::path& from, const std::filesystem::path& to,
               Transfer how) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (how == Transfer::kLink) {
    if (fs::exists(to, ec) && fs::equivalent(from, to, ec)) return;
    fs::remove(to, ec);
    fs::create_hard_link(from, to, ec);
    if (!ec) return;
  }
  fs::copy_file(from, to, fs::copy_options::overwrite_existing, ec);
  if (ec) throw Error("io", "cannot place artifact: " + ec.message(), {.file = from.string()});
}

void TransferArtifacts(const std::filesystem::path& from_root, const std::filesystem::path& to_root,
                       ClipId clip, Transfer how) {
  namespace fs = std::filesystem;
  const auto from = from_root / "artifacts" / std::to_string(clip);
  if (!fs::is_directory(from)) return;
  const auto to = to_root / "artifacts" / std::to_string(clip);
  std::error_code ec;
  fs::create_directories(to, ec);
  for (auto it = fs::recursive_directory_iterator(from, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    const auto target = to / fs::relative(it->path(), from);
    if (it->is_directory()) {
      fs::create_directories(target, ec);
    } else if (it->is_regular_file()) {
      PlaceFile(it->path(), target, how);
    }
  }
  if (ec) throw Error("io", "cannot read artifacts: " + ec.message(), {.file = from.string()});
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
    for (ClipId c : spec.clips) {
      TransferArtifacts(db.root(), info.db.parent_path(), c, Transfer::kCopy);
    }
    made.push_back(info);
  }
  return made;
}

Database::MergeStats MergeShard(Database& db, const std::filesystem::path& shard_db) {
  // Rows first: a refused shard (foreign, other pipeline or config) must not
  // leave its files in this database's artifact folder.
  Database::MergeStats stats = db.MergeShard(shard_db);
  Database shard(shard_db);
  for (const ClipRecord& clip : shard.ListClips()) {
    TransferArtifacts(shard.root(), db.root(), clip.id, Transfer::kLink);
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
