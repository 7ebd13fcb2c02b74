// `doasido status --clips`: one line per clip saying where it stopped in the
// pipeline and why (a reject, a failure, a flag waiting for review, or still
// queued), the table the demo ends with. Stages the deciding verdict left
// unmeasured (verdict not_measured) are named after the reason.
#include <cstdio>
#include <map>

#include "cli/commands.h"
#include "db/database.h"

namespace doasido::cli {
namespace {

// The first line of `text`, at most `width` characters.
std::string Short(const std::string& text, size_t width) {
  std::string line = text.substr(0, text.find('\n'));
  if (line.size() > width) line = line.substr(0, width - 3) + "...";
  return line;
}

}  // namespace

void PrintClipTable(Database& db) {
  const std::vector<std::string> pipeline = db.Pipeline();
  std::map<ClipId, std::map<std::string, StageRunRow>> runs;
  std::map<ClipId, std::string> names;
  for (const StageRunRow& r : db.ListRuns({})) {
    runs[r.clip_id][r.stage] = r;
    names[r.clip_id] = r.external_id;
  }
  std::printf("%-6s %-24s %-20s %-8s %s\n", "clip", "id", "stopped at", "outcome", "why");
  for (const auto& [clip, by_stage] : runs) {
    std::string stage = "(not started)", outcome, why, flagged, unmeasured;
    bool stopped = false;
    for (const std::string& name : pipeline) {
      const auto it = by_stage.find(name);
      if (it == by_stage.end()) break;
      const StageRunRow& r = it->second;
      stage = name;
      outcome = r.state == RunState::kDone ? r.verdict : ToString(r.state);
      why = r.state == RunState::kDone ? r.reason : r.error;
      stopped = r.state != RunState::kDone || r.verdict == "reject";
      if (stopped) break;
      if (r.verdict == "flag" && flagged.empty()) flagged = name + ": " + r.reason;
      // A stage whose measurement the deciding verdict made unnecessary
      // neither passed nor stopped the clip: said beside the reason.
      if (r.state == RunState::kDone && r.verdict == ToString(Verdict::kNotMeasured)) {
        unmeasured += (unmeasured.empty() ? "" : ", ") + name;
      }
    }
    if (stopped && !unmeasured.empty()) why += " (not measured: " + unmeasured + ")";
    if (!stopped && stage == pipeline.back()) {
      if (why.empty()) why = "went through every stage";
    } else if (!stopped && !flagged.empty()) {
      outcome = "flag";
      why = flagged + " (waits for a person: doasido review serve)";
    }
    std::printf("%-6lld %-24s %-20s %-8s %s\n", static_cast<long long>(clip),
                Short(names[clip], 24).c_str(), stage.c_str(), outcome.c_str(), Short(why, 70).c_str());
  }
}

}  // namespace doasido::cli
