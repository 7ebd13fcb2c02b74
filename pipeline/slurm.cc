#include "pipeline/slurm.h"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace doasido::pipeline {
namespace {

// Single-quoted for the shell.
std::string Quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Runs a command, returning its exit status and what it printed (stdout and stderr).
int Capture(const std::string& command, std::string& output) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) output.append(buffer.data(), n);
  const int status = pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

void WriteFile(const std::filesystem::path& path, const std::string& text, bool executable) {
  std::ofstream out(path);
  out << text;
  if (!out) throw Error("io", "cannot write", {.file = path.string()});
  out.close();
  if (executable) {
    std::filesystem::permissions(path, std::filesystem::perms::owner_exec |
                                           std::filesystem::perms::group_exec,
                                 std::filesystem::perm_options::add);
  }
}

std::string Directives(const SlurmOptions& o) {
  std::ostringstream s;
  if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
  if (!o.account.empty()) s << "#SBATCH --account=" << o.account << "\n";
  if (!o.mem.empty()) s << "#SBATCH --mem=" << o.mem << "\n";
  if (!o.time.empty()) s << "#SBATCH --time=" << o.time << "\n";
  return s.str();
}

}  // namespace

SlurmScripts WriteSlurmScripts(const std::filesystem::path& out, const std::filesystem::path& parent,
                               const std::vector<std::filesystem::path>& shard_dbs,
                               const SlurmOptions& o) {
  if (shard_dbs.empty()) throw Error("slurm", "no shards to submit", {.file = out.string()});
  std::filesystem::create_directories(out / "logs");
  SlurmScripts paths{out / "array.sbatch", out / "merge.sbatch", out / "shards.txt"};
  std::string list;
  for (const auto& db : shard_dbs) list += std::filesystem::absolute(db).string() + "\n";
  WriteFile(paths.shards, list, false);

  const std::string doasido = Quote(std::filesystem::absolute(o.doasido).string());
  const std::string config =
      o.config.empty() ? "" : " --config " + Quote(std::filesystem::absolute(o.config).string());
  std::ostringstream array;
  array << "#!/bin/bash\n"
        << "# One doasido shard per array task (doasido slurm submit). Edit freely;\n"
        << "# `doasido slurm resume` resubmits the tasks whose shard is unfinished.\n"
        << "#SBATCH --job-name=doasido-shards\n"
        << "#SBATCH --array=0-" << shard_dbs.size() - 1 << "\n"
        << "#SBATCH --cpus-per-task=" << o.cpus_per_task << "\n"
        << "#SBATCH --output=" << (out / "logs" / "shard-%a.out").string() << "\n"
        << Directives(o) << "set -euo pipefail\n"
        << "SHARD_DB=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" " << Quote(paths.shards.string())
        << ")\n"
        << "JOBS=${SLURM_CPUS_PER_TASK:-1}\n";
  if (o.scratch) {
    array << "SHARD_DIR=$(dirname \"$SHARD_DB\")\n"
          << "WORK=${SLURM_TMPDIR:-${TMPDIR:-/tmp}}/doasido-${SLURM_ARRAY_JOB_ID}-"
             "${SLURM_ARRAY_TASK_ID}\n"
          << "mkdir -p \"$WORK\" && cp -a \"$SHARD_DIR/.\" \"$WORK/\"\n"
          << "# The shard goes back to shared storage however the task ends.\n"
          << "trap 'cp -a \"$WORK/.\" \"$SHARD_DIR/\" && rm -rf \"$WORK\"' EXIT\n"
          << "RUN_DB=\"$WORK/$(basename \"$SHARD_DB\")\"\n";
  } else {
    array << "RUN_DB=$SHARD_DB\n";
  }
  array << "# One task at a time works on a shard: runs a killed task held go back to the queue.\n"
        << doasido << " queue release --db \"$RUN_DB\"\n"
        << doasido << " run --db \"$RUN_DB\" --jobs \"$JOBS\"" << config << "\n";
  WriteFile(paths.array, array.str(), true);

  std::ostringstream merge;
  merge << "#!/bin/bash\n"
        << "# Folds every shard back into the parent once the array has ended.\n"
        << "#SBATCH --job-name=doasido-merge\n"
        << "#SBATCH --cpus-per-task=1\n"
        << "#SBATCH --output=" << (out / "logs" / "merge.out").string() << "\n"
        << Directives(o) << "set -euo pipefail\n"
        << "mapfile -t SHARDS < " << Quote(paths.shards.string()) << "\n"
        << doasido << " merge --db " << Quote(std::filesystem::absolute(parent).string())
        << " \"${SHARDS[@]}\"\n";
  WriteFile(paths.merge, merge.str(), true);
  return paths;
}

std::string Sbatch(const std::filesystem::path& script, const std::string& array,
                   const std::string& after) {
  std::string command = "sbatch --parsable";
  if (!array.empty()) command += " --array=" + array;
  if (!after.empty()) command += " --dependency=afterany:" + after;
  command += " " + Quote(script.string());
  std::string output;
  const int status = Capture(command, output);
  while (!output.empty() && (output.back() == '\n' || output.back() == '\r')) output.pop_back();
  if (status != 0 || output.empty()) {
    throw Error("slurm", "sbatch failed (exit " + std::to_string(status) + "): " + output,
                {.file = script.string()});
  }
  // --parsable prints "<id>" or "<id>;<cluster>".
  return output.substr(0, output.find(';'));
}

std::map<std::string, std::string> SlurmTaskStates(const std::vector<std::string>& jobs) {
  std::map<std::string, std::string> states;
  if (jobs.empty()) return states;
  std::string list;
  for (const auto& j : jobs) list += (list.empty() ? "" : ",") + j;
  std::string output;
  if (Capture("squeue -h -r -o '%i %T' -j " + Quote(list), output) != 0) return states;
  std::istringstream lines(output);
  std::string id, state;
  while (lines >> id >> state) states[id] = state;
  return states;
}

std::filesystem::path SelfExecutable() {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path("doasido") : p;
}

}  // namespace doasido::pipeline
