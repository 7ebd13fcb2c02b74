// A one-node Slurm cluster on loopback, for tests/cli_slurm_test.cc and
// bench/pipeline_shard_bench.cc: Debian's munged, slurmctld and slurmd
// (installed by scripts/setup.sh) run as root from testing/slurm/slurm.conf.in
// with a fresh key, free ports and the machine's CPUs, two partitions (test,
// the default, and gpu) and one "gpu" GRES, for the lifetime of
// the object; they are stopped by their pids when it is destroyed.
// SLURM_CONF is set in this process's environment so that sbatch, squeue and
// the doasido commands it starts talk to this cluster.
#pragma once

#include <filesystem>
#include <string>

namespace doasido::testing {

// Runs a shell command and returns what it printed (stdout and stderr).
std::string Shell(const std::string& command);

class LoopbackSlurm {
 public:
  // Starts the daemons with their state, logs and pid files under `dir`.
  explicit LoopbackSlurm(const std::filesystem::path& dir);
  ~LoopbackSlurm();
  LoopbackSlurm(const LoopbackSlurm&) = delete;
  LoopbackSlurm& operator=(const LoopbackSlurm&) = delete;

  // True once the node takes jobs (within `seconds`).
  bool WaitIdle(double seconds) const;
  // True once no job is queued or running (within `seconds`).
  bool WaitEmpty(double seconds) const;
  // What the daemons printed and logged, for a failure message.
  std::string Logs() const;

 private:
  std::filesystem::path dir_;
  std::string log_;
};

}  // namespace doasido::testing
