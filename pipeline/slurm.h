// Running shards as Slurm job arrays (sbatch), one per stage group
// (pipeline/slurm_groups.h; one group of the whole pipeline by default),
// with a merge job that waits for the last array (afterany) and folds every
// shard back.
//
// Task i of a group's array runs `doasido run [--stages <the group's>]` on
// the i-th line of <out>/shards.txt with --jobs from SLURM_CPUS_PER_TASK; with `scratch` it copies the shard
// folder to node-local disk ($SLURM_TMPDIR, else $TMPDIR, else /tmp), runs
// there and copies it back when the task ends (also on failure). A task that
// failed or was preempted is resubmitted with ResubmitTasks: its shard's
// queue continues where it stopped (leases of the killed worker expire).
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "pipeline/slurm_groups.h"

namespace doasido::pipeline {

struct SlurmOptions {
  // The resources of a group that does not set its own (--partition,
  // --cpus-per-task, --mem, --time); `stages` and `name` are unused.
  SlurmGroup defaults;
  std::string account;         // --account
  bool scratch = false;        // run each shard on node-local disk
  std::filesystem::path config;   // --config for doasido run, empty: none
  std::filesystem::path doasido;  // the doasido executable the tasks run
};

struct SlurmScripts {
  // Per group: <out>/array.sbatch for the one group of the whole pipeline,
  // else <out>/group-<number>-<name>.sbatch.
  std::vector<std::filesystem::path> groups;
  std::filesystem::path merge;   // <out>/merge.sbatch
  std::filesystem::path shards;  // <out>/shards.txt: one shard database per line
};

// Writes a script per group, the merge script and the shard list into
// `out`. `parent` is the database the merge job folds the shards into.
SlurmScripts WriteSlurmScripts(const std::filesystem::path& out, const std::filesystem::path& parent,
                               const std::vector<std::filesystem::path>& shard_dbs,
                               const std::vector<SlurmGroup>& groups, const SlurmOptions& options);

// Runs `sbatch --parsable [--array=...] [--dependency=<dependency>] script`
// and returns the job id. `array` empty: the script's own range;
// `dependency` e.g. "aftercorr:123" or "afterany:123:124". Throws
// Error("slurm") with sbatch's message.
std::string Sbatch(const std::filesystem::path& script, const std::string& array = "",
                   const std::string& dependency = "");

// Cancels the given jobs or tasks ("<job>" or "<job>_<task>"). Throws
// Error("slurm") with scancel's message.
void Scancel(const std::vector<std::string>& ids);

struct SlurmTask {
  std::string state;   // PENDING, RUNNING, ...
  std::string reason;  // squeue's %r: Dependency, DependencyNeverSatisfied, None, ...
};
// Slurm's state of each task of the given array jobs, by "<job>_<task>",
// from squeue. Tasks that left the queue are absent. Empty when squeue is
// not installed or fails.
std::map<std::string, SlurmTask> SlurmTaskStates(const std::vector<std::string>& jobs);

// Path of the running executable.
std::filesystem::path SelfExecutable();

}  // namespace doasido::pipeline
