// Stage groups on Slurm: the pipeline cut into groups of consecutive stages,
// each submitted as its own job array over the same shards with its own
// resources (filters on CPU nodes, the model stages on GPU nodes, ...).
// Task i of a group waits for task i of the group before it (sbatch
// --dependency=aftercorr: per task, and only after that task succeeded),
// and one merge job waits for the last group's array (afterany).
//
// On the command line a group is "STAGES [key=value ...]" (docs/cluster.md):
//   STAGES  FIRST..LAST (inclusive), a,b,c, or one stage
//   keys    name, partition, cpus, mem, time, gres, gpus (gpus=N is gres=gpu:N)
// e.g. --group 'probe..camera_motion partition=cpu cpus=2'
//      --group 'bundle name=gpu partition=gpu gpus=1 mem=16G time=02:00:00'
//      --group 'recon..retarget_kinematic partition=cpu'
#pragma once

#include <string>
#include <vector>

#include "core/config.h"

namespace doasido::pipeline {

struct SlurmGroup {
  std::string name;                 // in script, job and log names; default g<number>
  std::vector<std::string> stages;  // empty: the whole pipeline (no --stages)
  std::string partition;            // empty: the cluster's default
  int cpus_per_task = 1;            // --cpus-per-task, and doasido run --jobs
  std::string mem;                  // --mem
  std::string time;                 // --time
  std::string gres;                 // --gres, e.g. gpu:1
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(SlurmGroup, name, stages, partition, cpus_per_task,
                                                mem, time, gres)

// Parses one --group spec against the pipeline; fields the spec leaves out
// come from `defaults`. Throws Error("bad_option") naming field "group" and
// the spec for an unknown stage or key, an empty or reversed range, or a
// bad value.
SlurmGroup ParseSlurmGroup(const std::string& spec, const std::vector<std::string>& pipeline,
                           const SlurmGroup& defaults, int number);

// Throws Error("bad_option") unless the groups take every stage of the
// pipeline exactly once, in pipeline order, under distinct names.
void CheckSlurmGroups(const std::vector<SlurmGroup>& groups,
                      const std::vector<std::string>& pipeline);

// Index of the group that runs `stage`; -1 when none does.
int GroupOfStage(const std::vector<SlurmGroup>& groups, const std::string& stage);

// What `slurm submit` keeps in the parent database's meta (JSON) for
// `slurm resume` and `status`: the groups and the --config and --scratch
// the tasks ran with.
inline constexpr const char* kSlurmSubmitMetaKey = "slurm_submit";
struct SlurmSubmission {
  std::vector<SlurmGroup> groups;
  std::string config;  // absolute; empty: none
  bool scratch = false;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(SlurmSubmission, groups, config, scratch)

}  // namespace doasido::pipeline
