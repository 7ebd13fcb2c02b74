// doasido shard | merge | slurm submit | slurm resume: the queue past one
// machine (pipeline/shard.h, pipeline/slurm.h).
#include <algorithm>
#include <cstdio>

#include "cli/commands.h"
#include "cli/option_checks.h"
#include "core/error.h"
#include "core/file_text.h"
#include "core/output_path.h"
#include "db/database.h"
#include "pipeline/shard.h"
#include "pipeline/slurm.h"
#include "pipeline/stage_registry.h"

namespace doasido::cli {
namespace {

struct ShardCliOptions {
  DbOptions db;
  int shards = 4;
  std::string out;
  std::vector<std::string> media_root;  // OLD=NEW
};

void AddShardOptions(CLI::App& cmd, ShardCliOptions& o) {
  AddDbOptions(cmd, o.db);
  cmd.add_option("--shards", o.shards, "How many shard databases to make")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd.add_option("--out", o.out, "Folder for the shard folders (default: <db folder>/shards)");
  cmd.add_option("--media-root", o.media_root,
                 "OLD=NEW: video paths under OLD are written as under NEW in the shards (media "
                 "mounted elsewhere on the nodes); repeatable");
}

// The parameter hash each pipeline stage runs with under the config.
Json StageHashes(Database& db, const Json& config) {
  Json hashes = Json::object();
  for (const auto& stage : db.Pipeline()) hashes[stage] = ParamHash(pipeline::MakeStage(stage, config)->Params());
  return hashes;
}

std::vector<pipeline::ShardInfo> MakeShards(Database& db, const ShardCliOptions& o) {
  pipeline::ShardOptions options;
  options.shards = o.shards;
  options.out_dir = o.out.empty() ? db.root() / "shards" : std::filesystem::path(o.out);
  // Shards never replace one another (Error("shard_exists")): an existing
  // folder is accepted, the guard keeps it off the inputs.
  CheckOutputPath({.path = options.out_dir,
                   .kind = OutputRequest::Kind::kFolder,
                   .option = "--out",
                   .what = "the shards",
                   .is_own_output = [](const std::filesystem::path&) { return true; },
                   .force = true,
                   .databases = {db.path()}});
  options.stage_hashes = StageHashes(db, LoadConfig(o.db));
  for (const auto& m : o.media_root) {
    const auto eq = m.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw Error("bad_option", "--media-root takes OLD=NEW, got '" + m + "'",
                  {.field = "media-root"});
    }
    options.media_map.emplace_back(m.substr(0, eq), m.substr(eq + 1));
  }
  const auto shards = pipeline::ShardQueue(db, options);
  for (const auto& s : shards) {
    std::printf("%s  %6lld clips  %5lld videos  %9lld frames  %s\n", s.name.c_str(),
                static_cast<long long>(s.clips), static_cast<long long>(s.videos),
                static_cast<long long>(s.frames), s.db.c_str());
  }
  return shards;
}

void AddShard(CLI::App& app) {
  auto o = std::make_shared<ShardCliOptions>();
  auto* cmd = app.add_subcommand(
      "shard", "Split the unfinished clips into self-contained shard databases");
  AddShardOptions(*cmd, *o);
  cmd->footer(
      "All clips of one video go to one shard; videos are balanced by frame count. The\n"
      "parent remembers which clip went where, leaves those clips to the shards, and\n"
      "refuses to shard them twice. Pass the --config the shards will run with: a merge\n"
      "refuses runs done with other parameters.\n\n"
      "Example (no Slurm: run each shard anywhere, then merge):\n"
      "  doasido shard --db work/doasido.db --shards 4 --out /scratch/shards\n"
      "  doasido run   --db /scratch/shards/shard-000/doasido.db --jobs 8   # on any machine\n"
      "  doasido merge --db work/doasido.db /scratch/shards/shard-*/doasido.db");
  cmd->callback([o] {
    Database db(o->db.db, Database::OpenMode::kExisting);
    MakeShards(db, *o);
  });
}

void AddMerge(CLI::App& app) {
  struct Options {
    DbOptions db;
    std::vector<std::string> shards;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("merge", "Fold shard databases back into their parent");
  AddDbOptions(*cmd, o->db);
  cmd->add_option("shards", o->shards, "Shard databases (made by doasido shard)")->required();
  cmd->footer(
      "Each shard's runs, measurements, verdicts, reviews, events and artifacts replace\n"
      "the parent's for its clips. Merging again changes nothing; a shard that is only\n"
      "partly done merges its done part (the rest stays the shard's to finish). A shard\n"
      "of another database, pipeline or configuration is refused by name; the other\n"
      "shards still merge, and the exit code is 1.\n\n"
      "Example:\n  doasido merge --db work/doasido.db work/shards/shard-*/doasido.db");
  cmd->callback([o] {
    Database db(o->db.db, Database::OpenMode::kExisting);
    int refused = 0, held_back = 0;
    for (const auto& path : o->shards) {
      try {
        const auto s = pipeline::MergeShard(db, path);
        std::printf("%s: %lld clips, %lld runs finished, %lld still open, %lld clips changed, "
                    "%lld events\n",
                    s.shard.c_str(), static_cast<long long>(s.clips),
                    static_cast<long long>(s.finished_runs), static_cast<long long>(s.open_runs),
                    static_cast<long long>(s.changed_clips), static_cast<long long>(s.events));
        if (s.handed_back > 0) {
          std::printf("%s: finished; its %lld clips are this database's again\n",
                      s.shard.c_str(), static_cast<long long>(s.handed_back));
        }
        for (const std::string& why : s.held_back) {
          std::fprintf(stderr, "%s: not merged: %s\n", s.shard.c_str(), why.c_str());
          ++held_back;
        }
      } catch (const Error& e) {
        std::fprintf(stderr, "refused: %s\n", e.what());
        ++refused;
      }
    }
    if (held_back > 0 && refused == 0) {
      throw Error("merge", std::to_string(held_back) +
                               " clips not merged: a file their rows record is missing (named above)");
    }
    if (refused > 0) {
      throw Error("merge", std::to_string(refused) + " of " + std::to_string(o->shards.size()) +
                               " shards refused");
    }
  });
}

struct SlurmCliOptions {
  ShardCliOptions shard;
  pipeline::SlurmOptions slurm;
  bool dry_run = false;
};

void AddSlurmOptions(CLI::App& cmd, SlurmCliOptions& o) {
  cmd.add_option("--partition", o.slurm.partition, "Slurm partition");
  cmd.add_option("--cpus-per-task", o.slurm.cpus_per_task, "CPUs per task (= doasido run --jobs)")->check(FiniteRange(1, 1024))
      ->capture_default_str()
      ->check(CLI::Range(1, 4096));
  cmd.add_option("--mem", o.slurm.mem, "Memory per task, e.g. 8G");
  cmd.add_option("--time", o.slurm.time, "Time limit per task, e.g. 04:00:00");
  cmd.add_option("--account", o.slurm.account, "Slurm account");
  cmd.add_flag("--scratch", o.slurm.scratch,
               "Run each shard on node-local disk and copy it back when the task ends");
  cmd.add_flag("--dry-run", o.dry_run, "Write and print the scripts; submit nothing");
}

// Submits the array (every task, or the listed ones) and a merge job after it.
void Submit(Database& db, const std::vector<Database::ShardRow>& shards,
            const pipeline::SlurmScripts& scripts, const std::vector<size_t>& tasks) {
  std::string list;
  for (size_t t : tasks) list += (list.empty() ? "" : ",") + std::to_string(t);
  const std::string array = pipeline::Sbatch(scripts.array, list);
  const std::string merge = pipeline::Sbatch(scripts.merge, "", array);
  for (size_t i = 0; i < shards.size(); ++i) {
    if (tasks.empty() || std::find(tasks.begin(), tasks.end(), i) != tasks.end()) {
      db.SetShardJob(shards[i].name, array, static_cast<std::int64_t>(i));
    }
  }
  std::printf("submitted array job %s (tasks %s) and merge job %s (afterany:%s)\n",
              array.c_str(), list.empty() ? "all" : list.c_str(), merge.c_str(), array.c_str());
}

void PrintFile(const std::filesystem::path& path) {
  std::printf("# ---- %s\n%s\n", path.c_str(), TryReadFile(path).value_or("").c_str());
}

pipeline::SlurmScripts Scripts(Database& db, const std::vector<Database::ShardRow>& shards,
                               SlurmCliOptions& o) {
  std::vector<std::filesystem::path> dbs;
  for (const auto& s : shards) dbs.push_back(s.path);
  o.slurm.doasido = pipeline::SelfExecutable();
  if (!o.shard.db.config.empty()) o.slurm.config = o.shard.db.config;
  const auto dir = shards.front().path.parent_path().parent_path();
  return pipeline::WriteSlurmScripts(dir, db.path(), dbs, o.slurm);
}

void AddSlurm(CLI::App& app) {
  auto* slurm = app.add_subcommand("slurm", "Run the queue as a Slurm job array and merge it back");
  slurm->require_subcommand(1);

  auto o = std::make_shared<SlurmCliOptions>();
  auto* submit = slurm->add_subcommand(
      "submit", "Shard the unfinished clips, submit one array task per shard and a merge job");
  AddShardOptions(*submit, o->shard);
  AddSlurmOptions(*submit, *o);
  submit->footer(
      "Writes <out>/array.sbatch, <out>/merge.sbatch and <out>/shards.txt, submits both\n"
      "with sbatch (the merge waits for the array: afterany) and prints their ids.\n"
      "Shard databases live on the shared filesystem but are only opened by one task\n"
      "at a time; with --scratch each task works on node-local disk. `doasido status`\n"
      "shows each shard's progress; `doasido slurm resume` resubmits unfinished shards.\n\n"
      "Example:\n"
      "  doasido slurm submit --db work/doasido.db --shards 64 --partition cpu \\\n"
      "      --cpus-per-task 8 --mem 16G --time 08:00:00 --scratch\n"
      "  doasido slurm submit --db work/doasido.db --shards 4 --dry-run   # scripts only");
  submit->callback([o] {
    Database db(o->shard.db.db, Database::OpenMode::kExisting);
    MakeShards(db, o->shard);
    std::vector<Database::ShardRow> fresh;
    for (const auto& row : db.ListShards()) {
      if (row.slurm_job.empty()) fresh.push_back(row);
    }
    const auto scripts = Scripts(db, fresh, *o);
    if (o->dry_run) {
      PrintFile(scripts.array);
      PrintFile(scripts.merge);
      return;
    }
    Submit(db, fresh, scripts, {});
  });

  auto r = std::make_shared<SlurmCliOptions>();
  auto* resume = slurm->add_subcommand(
      "resume", "Resubmit the array tasks whose shard has unfinished runs, and a merge job");
  AddDbOptions(*resume, r->shard.db);
  AddSlurmOptions(*resume, *r);
  resume->footer(
      "For a task that failed, hit its time limit or was preempted: its shard's queue\n"
      "continues where it stopped (the killed worker's leases expire). Shards whose\n"
      "task is still queued or running are left alone.\n\n"
      "Example:\n  doasido slurm resume --db work/doasido.db --time 04:00:00");
  resume->callback([r] {
    Database db(r->shard.db.db, Database::OpenMode::kExisting);
    const auto shards = db.ListShards();
    if (shards.empty()) throw Error("no_shards", "this database has no shards", {.file = db.path().string()});
    std::vector<std::string> jobs;
    for (const auto& s : shards) {
      if (!s.slurm_job.empty()) jobs.push_back(s.slurm_job);
    }
    const auto progress = pipeline::ReadShardProgress(db, pipeline::SlurmTaskStates(jobs));
    std::vector<size_t> tasks;
    for (size_t i = 0; i < progress.size(); ++i) {
      if (progress[i].runs_open > 0 && progress[i].slurm_state.empty()) tasks.push_back(i);
    }
    if (tasks.empty()) {
      std::printf("every shard is finished or still queued: nothing to resume\n");
      return;
    }
    const auto scripts = Scripts(db, shards, *r);
    if (r->dry_run) {
      for (size_t t : tasks) std::printf("would resubmit task %zu (%s)\n", t, shards[t].name.c_str());
      return;
    }
    Submit(db, shards, scripts, tasks);
  });
}

}  // namespace

void AddShardCommands(CLI::App& app) {
  AddShard(app);
  AddMerge(app);
  AddSlurm(app);
}

void PrintShardTable(Database& db) {
  const auto shards = db.ListShards();
  if (shards.empty()) return;
  std::vector<std::string> jobs;
  for (const auto& s : shards) {
    if (!s.slurm_job.empty()) jobs.push_back(s.slurm_job);
  }
  std::printf("\n%-10s %7s %9s %7s %7s %-12s %-10s %s\n", "shard", "clips", "finished", "failed",
              "open", "slurm", "merged", "database");
  for (const auto& p : pipeline::ReadShardProgress(db, pipeline::SlurmTaskStates(jobs))) {
    const std::string slurm =
        p.shard.slurm_job.empty() ? "-"
        : p.slurm_state.empty()   ? p.shard.slurm_job + " ended"
                                  : p.slurm_state;
    std::printf("%-10s %7lld %9lld %7lld %7lld %-12s %-10s %s%s\n", p.shard.name.c_str(),
                static_cast<long long>(p.shard.clips), static_cast<long long>(p.clips_finished),
                static_cast<long long>(p.clips_failed), static_cast<long long>(p.runs_open),
                slurm.c_str(), p.merged ? "yes" : (p.shard.merged_at ? "partly" : "no"),
                p.shard.path.c_str(), p.file_found ? "" : " (missing)");
  }
}

}  // namespace doasido::cli
