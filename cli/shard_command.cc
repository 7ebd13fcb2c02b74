// doasido shard | merge | slurm submit | slurm resume: the queue past one
// machine (pipeline/shard.h, pipeline/slurm.h).
#include <algorithm>
#include <cstdio>
#include <map>
#include <optional>
#include <set>

#include "cli/commands.h"
#include "cli/option_checks.h"
#include "core/error.h"
#include "core/file_text.h"
#include "core/output_path.h"
#include "db/database.h"
#include "pipeline/shard.h"
#include "pipeline/slurm.h"
#include "stages/stage_registry.h"

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
                 "mounted elsewhere on the nodes); repeatable")
      ->allow_extra_args(false);
}

// The parameter hash each pipeline stage runs with under the config.
Json StageHashes(Database& db, const Json& config) {
  Json hashes = Json::object();
  for (const auto& stage : db.Pipeline()) hashes[stage] = stages::ResultHash(*stages::MakeStage(stage, config));
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
  std::vector<std::string> groups;  // --group specs (submit)
  bool dry_run = false;
  CLI::Option* cpus = nullptr;      // to tell a given --cpus-per-task from the default
};

void AddSlurmOptions(CLI::App& cmd, SlurmCliOptions& o) {
  cmd.add_option("--partition", o.slurm.defaults.partition, "Slurm partition");
  o.cpus = cmd.add_option("--cpus-per-task", o.slurm.defaults.cpus_per_task,
                          "CPUs per task (= doasido run --jobs)")
               ->capture_default_str()
               ->check(FiniteRange(1, 4096));
  cmd.add_option("--mem", o.slurm.defaults.mem, "Memory per task, e.g. 8G");
  cmd.add_option("--time", o.slurm.defaults.time, "Time limit per task, e.g. 04:00:00");
  cmd.add_option("--account", o.slurm.account, "Slurm account");
  cmd.add_flag("--scratch", o.slurm.scratch,
               "Run each shard on node-local disk and copy it back when the task ends");
  cmd.add_flag("--dry-run", o.dry_run, "Write and print the scripts; submit nothing");
}

std::string Join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : separator) + p;
  return out;
}

// The groups of a new submission: one of the whole pipeline without --group.
std::vector<pipeline::SlurmGroup> SubmitGroups(Database& db, const SlurmCliOptions& o) {
  pipeline::SlurmGroup defaults = o.slurm.defaults;
  defaults.stages.clear();
  if (o.groups.empty()) {
    defaults.name = "all";
    return {defaults};
  }
  std::vector<pipeline::SlurmGroup> groups;
  for (const auto& spec : o.groups) {
    groups.push_back(pipeline::ParseSlurmGroup(spec, db.Pipeline(), defaults,
                                               static_cast<int>(groups.size()) + 1));
  }
  pipeline::CheckSlurmGroups(groups, db.Pipeline());
  return groups;
}

std::optional<pipeline::SlurmSubmission> StoredSubmission(Database& db) {
  const auto stored = db.GetMeta(pipeline::kSlurmSubmitMetaKey);
  if (!stored) return std::nullopt;  // submitted before stage groups existed
  return Json::parse(*stored).get<pipeline::SlurmSubmission>();
}

// The groups the parent was submitted with (its meta), with the resources
// given to `slurm resume` in place of theirs; the submission's --config and
// --scratch unless given again.
std::vector<pipeline::SlurmGroup> ResumeGroups(Database& db, SlurmCliOptions& o) {
  const auto stored = StoredSubmission(db);
  if (!stored) return SubmitGroups(db, o);
  if (o.shard.db.config.empty()) o.shard.db.config = stored->config;
  o.slurm.scratch = o.slurm.scratch || stored->scratch;
  std::vector<pipeline::SlurmGroup> groups = stored->groups;
  const auto& d = o.slurm.defaults;
  for (auto& g : groups) {
    if (!d.partition.empty()) g.partition = d.partition;
    if (!d.mem.empty()) g.mem = d.mem;
    if (!d.time.empty()) g.time = d.time;
    if (o.cpus && o.cpus->count() > 0) g.cpus_per_task = d.cpus_per_task;
  }
  return groups;
}

// Submits, per first group, the chain of group arrays from it to the last
// over `tasks` (empty: all), each task after the same task of the group
// before (aftercorr), then one merge job after every chain's last array.
void Submit(Database& db, const std::vector<Database::ShardRow>& shards,
            const pipeline::SlurmScripts& scripts,
            const std::vector<pipeline::SlurmGroup>& groups,
            const std::map<int, std::vector<size_t>>& first_group_tasks) {
  std::vector<std::string> last_arrays;
  for (const auto& [first, tasks] : first_group_tasks) {
    std::vector<std::string> task_ids;
    for (size_t t : tasks) task_ids.push_back(std::to_string(t));
    const std::string list = Join(task_ids, ",");
    std::vector<std::string> chain;
    for (size_t g = static_cast<size_t>(first); g < groups.size(); ++g) {
      const std::string after = chain.empty() ? "" : "aftercorr:" + chain.back();
      chain.push_back(pipeline::Sbatch(scripts.groups[g], list, after));
      if (groups.size() > 1) {
        std::printf("submitted group %s: array job %s (tasks %s)%s\n", groups[g].name.c_str(),
                    chain.back().c_str(), list.empty() ? "all" : list.c_str(),
                    after.empty() ? "" : (", each task after its own in " + after).c_str());
      }
    }
    last_arrays.push_back(chain.back());
    for (size_t i = 0; i < shards.size(); ++i) {
      if (!tasks.empty() && std::find(tasks.begin(), tasks.end(), i) == tasks.end()) continue;
      std::vector<std::string> jobs = pipeline::ShardJobs(shards[i]);
      jobs.resize(groups.size());
      for (size_t g = static_cast<size_t>(first); g < groups.size(); ++g) {
        jobs[g] = chain[g - static_cast<size_t>(first)];
      }
      db.SetShardJob(shards[i].name, Join(jobs, ","), static_cast<std::int64_t>(i));
    }
    if (groups.size() == 1) {
      std::printf("submitted array job %s (tasks %s)", chain.back().c_str(),
                  list.empty() ? "all" : list.c_str());
    }
  }
  const std::string after = "afterany:" + Join(last_arrays, ":");
  const std::string merge = pipeline::Sbatch(scripts.merge, "", after);
  std::printf("%smerge job %s (%s)\n", groups.size() == 1 ? " and " : "submitted ",
              merge.c_str(), after.c_str());
}

void PrintFile(const std::filesystem::path& path) {
  std::printf("# ---- %s\n%s\n", path.c_str(), TryReadFile(path).value_or("").c_str());
}

pipeline::SlurmScripts Scripts(Database& db, const std::vector<Database::ShardRow>& shards,
                               const std::vector<pipeline::SlurmGroup>& groups,
                               SlurmCliOptions& o) {
  std::vector<std::filesystem::path> dbs;
  for (const auto& s : shards) dbs.push_back(s.path);
  o.slurm.doasido = pipeline::SelfExecutable();
  if (!o.shard.db.config.empty()) o.slurm.config = o.shard.db.config;
  const auto dir = shards.front().path.parent_path().parent_path();
  return pipeline::WriteSlurmScripts(dir, db.path(), dbs, groups, o.slurm);
}

// Every array job of every shard, for squeue.
std::vector<std::string> AllShardJobs(const std::vector<Database::ShardRow>& shards) {
  std::set<std::string> jobs;
  for (const auto& s : shards) {
    for (const auto& j : pipeline::ShardJobs(s)) {
      if (!j.empty()) jobs.insert(j);
    }
  }
  return {jobs.begin(), jobs.end()};
}

// What `slurm resume` does for one shard: nothing (empty), or the tasks to
// cancel first (stuck behind a task that failed) and the group to start at.
struct ResumePlan {
  bool resubmit = false;
  int first_group = 0;
  std::vector<std::string> cancel;
};
ResumePlan PlanResume(const pipeline::ShardProgress& p,
                      const std::vector<pipeline::SlurmGroup>& groups,
                      const std::map<std::string, pipeline::SlurmTask>& states) {
  ResumePlan plan;
  if (p.runs_open == 0) return plan;
  // aftercorr: a task whose predecessor failed or was cancelled waits forever.
  const bool stuck = p.slurm_group >= 0 && p.slurm_state == "PENDING" &&
                     p.slurm_reason == "DependencyNeverSatisfied";
  if (p.slurm_group >= 0 && !stuck) return plan;  // queued or running: leave it
  plan.resubmit = true;
  plan.first_group = static_cast<int>(groups.size()) - 1;
  for (const auto& stage : p.open_stages) {
    const int g = pipeline::GroupOfStage(groups, stage);
    if (g >= 0) plan.first_group = std::min(plan.first_group, g);
  }
  const auto jobs = pipeline::ShardJobs(p.shard);
  for (const auto& job : jobs) {
    const std::string id = job + "_" + std::to_string(p.shard.slurm_task.value_or(0));
    if (!job.empty() && states.count(id)) plan.cancel.push_back(id);
  }
  return plan;
}

// `slurm submit`: shards the unfinished clips, writes the scripts and submits
// them (or prints them with --dry-run).
void RunSlurmSubmit(SlurmCliOptions& o) {
  Database db(o.shard.db.db, Database::OpenMode::kExisting);
  const auto groups = SubmitGroups(db, o);  // checked before anything is sharded
  MakeShards(db, o.shard);
  std::vector<Database::ShardRow> fresh;
  for (const auto& row : db.ListShards()) {
    if (row.slurm_job.empty()) fresh.push_back(row);
  }
  const auto scripts = Scripts(db, fresh, groups, o);
  if (o.dry_run) {
    for (const auto& g : scripts.groups) PrintFile(g);
    PrintFile(scripts.merge);
    return;
  }
  const pipeline::SlurmSubmission submission{
      groups, o.slurm.config.empty() ? "" : std::filesystem::absolute(o.slurm.config).string(),
      o.slurm.scratch};
  db.SetMeta(pipeline::kSlurmSubmitMetaKey, Json(submission).dump());
  Submit(db, fresh, scripts, groups, {{0, {}}});
}

// `slurm resume`: resubmits the shards with open runs from their first open
// stage group, cancelling the tasks that wait for a failed one.
void RunSlurmResume(SlurmCliOptions& r) {
  Database db(r.shard.db.db, Database::OpenMode::kExisting);
  const auto shards = db.ListShards();
  if (shards.empty()) throw Error("no_shards", "this database has no shards", {.file = db.path().string()});
  const auto groups = ResumeGroups(db, r);
  const auto states = pipeline::SlurmTaskStates(AllShardJobs(shards));
  const auto progress = pipeline::ReadShardProgress(db, states);
  std::map<int, std::vector<size_t>> first_group_tasks;
  std::vector<std::string> cancel;
  for (size_t i = 0; i < progress.size(); ++i) {
    const ResumePlan plan = PlanResume(progress[i], groups, states);
    if (!plan.resubmit) continue;
    first_group_tasks[plan.first_group].push_back(i);
    cancel.insert(cancel.end(), plan.cancel.begin(), plan.cancel.end());
    std::printf("%s task %zu (%s) from group %s%s\n", r.dry_run ? "would resubmit" : "resubmitting",
                i, shards[i].name.c_str(), groups[static_cast<size_t>(plan.first_group)].name.c_str(),
                plan.cancel.empty() ? "" : (", cancelling " + Join(plan.cancel, " ")).c_str());
  }
  if (first_group_tasks.empty()) {
    std::printf("every shard is finished or still queued: nothing to resume\n");
    return;
  }
  if (r.dry_run) return;
  const auto scripts = Scripts(db, shards, groups, r);
  pipeline::Scancel(cancel);
  Submit(db, shards, scripts, groups, first_group_tasks);
}

void AddSlurm(CLI::App& app) {
  auto* slurm = app.add_subcommand("slurm", "Run the queue as Slurm job arrays and merge it back");
  slurm->require_subcommand(1);

  auto o = std::make_shared<SlurmCliOptions>();
  auto* submit = slurm->add_subcommand(
      "submit", "Shard the unfinished clips, submit one array task per shard (per stage group) "
                "and a merge job");
  AddShardOptions(*submit, o->shard);
  AddSlurmOptions(*submit, *o);
  submit->add_option(
      "--group", o->groups,
      "Stage group 'STAGES [key=value ...]', repeatable, in pipeline order: STAGES is FIRST..LAST, "
      "a,b,c or one stage; keys name, partition, cpus, mem, time, gres, gpus (gpus=N means "
      "gres=gpu:N); unset keys take --partition, --cpus-per-task, --mem, --time");
  submit->footer(
      "Writes <out>/shards.txt, a script per stage group (<out>/array.sbatch without\n"
      "--group, else <out>/group-<n>-<name>.sbatch) and <out>/merge.sbatch, submits them\n"
      "with sbatch and prints their ids. Each group is a job array over the same shards;\n"
      "task i of a group starts once task i of the group before it has succeeded\n"
      "(aftercorr), and the merge waits for the last group's array (afterany).\n"
      "Shard databases live on the shared filesystem but are only opened by one task\n"
      "at a time; with --scratch each task works on node-local disk. `doasido status`\n"
      "shows each shard's progress; `doasido slurm resume` resubmits unfinished shards.\n\n"
      "Examples:\n"
      "  doasido slurm submit --db work/doasido.db --shards 64 --partition cpu \\\n"
      "      --cpus-per-task 8 --mem 16G --time 08:00:00 --scratch\n"
      "  doasido slurm submit --db work/doasido.db --shards 64 --partition cpu --time 04:00:00 \\\n"
      "      --group 'probe..camera_motion cpus=4' \\\n"
      "      --group 'bundle name=gpu partition=gpu gpus=1 mem=32G' \\\n"
      "      --group 'recon..retarget_kinematic name=recon cpus=8'\n"
      "  doasido slurm submit --db work/doasido.db --shards 4 --dry-run   # scripts only");
  submit->callback([o] { RunSlurmSubmit(*o); });

  auto r = std::make_shared<SlurmCliOptions>();
  auto* resume = slurm->add_subcommand(
      "resume", "Resubmit the array tasks whose shard has unfinished runs, and a merge job");
  AddDbOptions(*resume, r->shard.db);
  AddSlurmOptions(*resume, *r);
  resume->footer(
      "For a task that failed, hit its time limit or was preempted: its shard's queue\n"
      "continues where it stopped (the killed worker's leases expire), from the first\n"
      "stage group with open runs, each later group after it as at submit. A shard whose\n"
      "task is queued or running is left alone; tasks of later groups that wait for a\n"
      "failed one (DependencyNeverSatisfied) are cancelled and submitted again. The\n"
      "groups keep their resources unless given here (--partition, --cpus-per-task,\n"
      "--mem, --time then apply to every group).\n\n"
      "Example:\n  doasido slurm resume --db work/doasido.db --time 04:00:00");
  resume->callback([r] { RunSlurmResume(*r); });
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
  std::vector<pipeline::SlurmGroup> groups;
  if (const auto stored = StoredSubmission(db)) groups = stored->groups;
  std::printf("\n%-10s %7s %9s %7s %7s %-16s %-10s %s\n", "shard", "clips", "finished", "failed",
              "open", "slurm", "merged", "database");
  for (const auto& p :
       pipeline::ReadShardProgress(db, pipeline::SlurmTaskStates(AllShardJobs(shards)))) {
    // With stage groups: the group of the shard's first task still queued.
    const std::string group =
        groups.size() > 1 && p.slurm_group >= 0 &&
                p.slurm_group < static_cast<int>(groups.size())
            ? groups[static_cast<size_t>(p.slurm_group)].name + ":"
            : "";
    const std::string slurm =
        p.shard.slurm_job.empty() ? "-"
        : p.slurm_state.empty()   ? pipeline::ShardJobs(p.shard).back() + " ended"
                                  : group + p.slurm_state;
    std::printf("%-10s %7lld %9lld %7lld %7lld %-16s %-10s %s%s\n", p.shard.name.c_str(),
                static_cast<long long>(p.shard.clips), static_cast<long long>(p.clips_finished),
                static_cast<long long>(p.clips_failed), static_cast<long long>(p.runs_open),
                slurm.c_str(), p.merged ? "yes" : (p.shard.merged_at ? "partly" : "no"),
                p.shard.path.c_str(), p.file_found ? "" : " (missing)");
  }
}

}  // namespace doasido::cli
