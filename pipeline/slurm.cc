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

std::string Directives(const SlurmGroup& g, const std::string& account) {
  std::ostringstream s;
  if (!g.partition.empty()) s << "#SBATCH --partition=" << g.partition << "\n";
  if (!account.empty()) s << "#SBATCH --account=" << account << "\n";
  if (!g.mem.empty()) s << "#SBATCH --mem=" << g.mem << "\n";
  if (!g.time.empty()) s << "#SBATCH --time=" << g.time << "\n";
  if (!g.gres.empty()) s << "#SBATCH --gres=" << g.gres << "\n";
  return s.str();
}

// The array script of one group: task i runs the group's stages on shard i.
std::string GroupScript(const std::filesystem::path& out, const SlurmScripts& paths,
                        const SlurmGroup& g, size_t shards, const SlurmOptions& o) {
  const std::string doasido = Quote(std::filesystem::absolute(o.doasido).string());
  const std::string config =
      o.config.empty() ? "" : " --config " + Quote(std::filesystem::absolute(o.config).string());
  std::string stages;
  for (const auto& s : g.stages) stages += (stages.empty() ? "" : ",") + s;
  const bool whole = g.stages.empty();
  std::ostringstream array;
  array << "#!/bin/bash\n"
        << "# One doasido shard per array task (doasido slurm submit)"
        << (whole ? "" : ", stages " + stages + " (group " + g.name + ")") << ". Edit freely;\n"
        << "# `doasido slurm resume` resubmits the tasks whose shard is unfinished.\n"
        << "#SBATCH --job-name=doasido-" << (whole ? std::string("shards") : g.name) << "\n"
        << "#SBATCH --array=0-" << shards - 1 << "\n"
        << "#SBATCH --cpus-per-task=" << g.cpus_per_task << "\n"
        << "#SBATCH --output="
        << (out / "logs" / ((whole ? std::string("shard") : g.name + "-shard") + "-%a.out")).string()
        << "\n"
        << Directives(g, o.account) << "set -euo pipefail\n"
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
        << doasido << " run --db \"$RUN_DB\" --jobs \"$JOBS\"" << config
        << (whole ? "" : " --stages " + stages) << "\n";
  return array.str();
}

}  // namespace

SlurmScripts WriteSlurmScripts(const std::filesystem::path& out, const std::filesystem::path& parent,
                               const std::vector<std::filesystem::path>& shard_dbs,
                               const std::vector<SlurmGroup>& groups, const SlurmOptions& o) {
  if (shard_dbs.empty()) throw Error("slurm", "no shards to submit", {.file = out.string()});
  if (groups.empty()) throw Error("slurm", "no stage groups to submit", {.file = out.string()});
  std::filesystem::create_directories(out / "logs");
  SlurmScripts paths{{}, out / "merge.sbatch", out / "shards.txt"};
  std::string list;
  for (const auto& db : shard_dbs) list += std::filesystem::absolute(db).string() + "\n";
  WriteFile(paths.shards, list, false);
  for (size_t i = 0; i < groups.size(); ++i) {
    const bool whole = groups.size() == 1 && groups[i].stages.empty();
    paths.groups.push_back(whole ? out / "array.sbatch"
                                 : out / ("group-" + std::to_string(i + 1) + "-" +
                                          groups[i].name + ".sbatch"));
    WriteFile(paths.groups.back(), GroupScript(out, paths, groups[i], shard_dbs.size(), o), true);
  }

  const std::string doasido = Quote(std::filesystem::absolute(o.doasido).string());
  SlurmGroup merge_resources = o.defaults;
  merge_resources.gres.clear();  // folding rows needs no GPU
  std::ostringstream merge;
  merge << "#!/bin/bash\n"
        << "# Folds every shard back into the parent once the last array has ended.\n"
        << "#SBATCH --job-name=doasido-merge\n"
        << "#SBATCH --cpus-per-task=1\n"
        << "#SBATCH --output=" << (out / "logs" / "merge.out").string() << "\n"
        << Directives(merge_resources, o.account) << "set -euo pipefail\n"
        << "mapfile -t SHARDS < " << Quote(paths.shards.string()) << "\n"
        << doasido << " merge --db " << Quote(std::filesystem::absolute(parent).string())
        << " \"${SHARDS[@]}\"\n";
  WriteFile(paths.merge, merge.str(), true);
  return paths;
}

std::string Sbatch(const std::filesystem::path& script, const std::string& array,
                   const std::string& dependency) {
  std::string command = "sbatch --parsable";
  if (!array.empty()) command += " --array=" + array;
  if (!dependency.empty()) command += " --dependency=" + Quote(dependency);
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

void Scancel(const std::vector<std::string>& ids) {
  if (ids.empty()) return;
  std::string command = "scancel";
  for (const auto& id : ids) command += " " + Quote(id);
  std::string output;
  if (Capture(command, output) != 0) {
    throw Error("slurm", "scancel failed: " + output);
  }
}

std::map<std::string, SlurmTask> SlurmTaskStates(const std::vector<std::string>& jobs) {
  std::map<std::string, SlurmTask> states;
  if (jobs.empty()) return states;
  std::string list;
  for (const auto& j : jobs) list += (list.empty() ? "" : ",") + j;
  std::string output;
  if (Capture("squeue -h -r -o '%i %T %r' -j " + Quote(list), output) != 0) {
    // squeue refuses the whole list when one job has left the controller.
    if (jobs.size() == 1) return states;
    for (const auto& j : jobs) states.merge(SlurmTaskStates({j}));
    return states;
  }
  std::istringstream lines(output);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string id;
    SlurmTask task;
    if (words >> id >> task.state) {
      words >> task.reason;
      states[id] = task;
    }
  }
  return states;
}

std::filesystem::path SelfExecutable() {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path("doasido") : p;
}

}  // namespace doasido::pipeline
