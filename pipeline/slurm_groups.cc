#include "pipeline/slurm_groups.h"

#include <algorithm>
#include <regex>
#include <set>
#include <sstream>

#include "core/error.h"

namespace doasido::pipeline {
namespace {

[[noreturn]] void Bad(const std::string& spec, const std::string& why) {
  throw Error("bad_option", "--group '" + spec + "': " + why, {.field = "group"});
}

size_t StageIndex(const std::string& spec, const std::vector<std::string>& pipeline,
                  const std::string& stage) {
  const auto it = std::find(pipeline.begin(), pipeline.end(), stage);
  if (it == pipeline.end()) Bad(spec, "'" + stage + "' is not a stage of the pipeline");
  return static_cast<size_t>(it - pipeline.begin());
}

std::vector<std::string> ParseStages(const std::string& spec, const std::string& word,
                                     const std::vector<std::string>& pipeline) {
  const auto dots = word.find("..");
  if (dots != std::string::npos) {
    const size_t first = StageIndex(spec, pipeline, word.substr(0, dots));
    const size_t last = StageIndex(spec, pipeline, word.substr(dots + 2));
    if (last < first) Bad(spec, "the range ends before it starts");
    return {pipeline.begin() + static_cast<long>(first), pipeline.begin() + static_cast<long>(last) + 1};
  }
  std::vector<std::string> stages;
  std::istringstream parts(word);
  for (std::string s; std::getline(parts, s, ',');) {
    StageIndex(spec, pipeline, s);
    stages.push_back(s);
  }
  return stages;
}

// Slurm's own syntax is checked by sbatch; this catches what would only
// fail once the array is queued (spaces, shell characters).
void RequireToken(const std::string& spec, const std::string& key, const std::string& value) {
  static const std::regex kToken("[A-Za-z0-9_.:,+-]+");
  if (!std::regex_match(value, kToken)) Bad(spec, key + " '" + value + "' is not a Slurm value");
}

}  // namespace

SlurmGroup ParseSlurmGroup(const std::string& spec, const std::vector<std::string>& pipeline,
                           const SlurmGroup& defaults, int number) {
  std::istringstream words(spec);
  std::string word;
  if (!(words >> word)) Bad(spec, "names no stages");
  SlurmGroup g = defaults;
  g.name = "g" + std::to_string(number);
  g.stages = ParseStages(spec, word, pipeline);
  while (words >> word) {
    const auto eq = word.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == word.size()) {
      Bad(spec, "'" + word + "' is not key=value");
    }
    const std::string key = word.substr(0, eq), value = word.substr(eq + 1);
    RequireToken(spec, key, value);
    if (key == "name") {
      g.name = value;
    } else if (key == "partition") {
      g.partition = value;
    } else if (key == "mem") {
      g.mem = value;
    } else if (key == "time") {
      g.time = value;
    } else if (key == "gres") {
      g.gres = value;
    } else if (key == "cpus" || key == "gpus") {
      int n = 0;
      try {
        size_t used = 0;
        n = std::stoi(value, &used);
        if (used != value.size()) n = 0;
      } catch (const std::exception&) {
      }
      if (n < 1 || n > 4096) Bad(spec, key + " must be a whole number in [1, 4096]");
      if (key == "cpus") g.cpus_per_task = n;
      else g.gres = "gpu:" + value;
    } else {
      Bad(spec, "unknown key '" + key + "' (name, partition, cpus, mem, time, gres, gpus)");
    }
  }
  return g;
}

void CheckSlurmGroups(const std::vector<SlurmGroup>& groups,
                      const std::vector<std::string>& pipeline) {
  std::vector<std::string> order;
  std::set<std::string> names;
  for (const auto& g : groups) {
    if (!names.insert(g.name).second) {
      throw Error("bad_option", "two groups are named '" + g.name + "'", {.field = "group"});
    }
    order.insert(order.end(), g.stages.begin(), g.stages.end());
  }
  if (order != pipeline) {
    std::string got, want;
    for (const auto& s : order) got += (got.empty() ? "" : ",") + s;
    for (const auto& s : pipeline) want += (want.empty() ? "" : ",") + s;
    throw Error("bad_option",
                "the groups must take the pipeline's stages once each, in order: they take " +
                    got + "; the pipeline is " + want,
                {.field = "group"});
  }
}

int GroupOfStage(const std::vector<SlurmGroup>& groups, const std::string& stage) {
  for (size_t i = 0; i < groups.size(); ++i) {
    if (groups[i].stages.empty() ||
        std::find(groups[i].stages.begin(), groups[i].stages.end(), stage) !=
            groups[i].stages.end()) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

}  // namespace doasido::pipeline
