// Running shards as a Slurm job array (sbatch), with a merge job that
// waits for the array (afterany) and folds every shard back.
//
// The array task i runs `doasido run` on the i-th line of <out>/shards.txt
// with --jobs from SLURM_CPUS_PER_TASK; with `scratch` it copies the shard
// folder to node-local disk ($SLURM_TMPDIR, else $TMPDIR, else /tmp), runs
// there and copies it back when the task ends (also on failure). A task that
// failed or was preempted is resubmitted with ResubmitTasks: its shard's
// queue continues where it stopped (leases of the killed worker expire).
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace doasido::pipeline {

struct SlurmOptions {
  std::string partition;       // --partition, empty: the cluster's default
  int cpus_per_task = 1;       // --cpus-per-task, and doasido run --jobs
  std::string mem;             // --mem, e.g. 8G; empty: the default
  std::string time;            // --time, e.g. 04:00:00; empty: the partition's limit
  std::string account;         // --account
  bool scratch = false;        // run each shard on node-local disk
  std::filesystem::path config;   // --config for doasido run, empty: none
  std::filesystem::path doasido;  // the doasido executable the tasks run
};

struct SlurmScripts {
  std::filesystem::path array;   // <out>/array.sbatch
  std::filesystem::path merge;   // <out>/merge.sbatch
  std::filesystem::path shards;  // <out>/shards.txt: one shard database per line
};

// Writes the two scripts and the shard list into `out`. `parent` is the
// database the merge job folds the shards into.
SlurmScripts WriteSlurmScripts(const std::filesystem::path& out, const std::filesystem::path& parent,
                               const std::vector<std::filesystem::path>& shard_dbs,
                               const SlurmOptions& options);

// Runs `sbatch --parsable [--array=...] [--dependency=afterany:<after>] script`
// and returns the job id. `array` empty: the script's own range. Throws
// Error("slurm") with sbatch's message.
std::string Sbatch(const std::filesystem::path& script, const std::string& array = "",
                   const std::string& after = "");

// Slurm's state of each task of the given array jobs, by "<job>_<task>"
// (PENDING, RUNNING, ...), from squeue. Tasks that left the queue are
// absent. Empty when squeue is not installed or fails.
std::map<std::string, std::string> SlurmTaskStates(const std::vector<std::string>& jobs);

// Path of the running executable.
std::filesystem::path SelfExecutable();

}  // namespace doasido::pipeline
