#include "dataset/settled_runs.h"

#include <map>

#include "core/error.h"

namespace doasido::dataset {
namespace {

using ReportRun = Database::ReportRun;

// Why `run`'s recorded inputs are not the clip's current upstream runs, or "".
std::string StaleInputs(const ReportRun& run,
                        const std::map<std::string, const ReportRun*>& by_stage) {
  if (!run.inputs.is_array()) return "";  // finished before inputs were recorded
  for (const Json& input : run.inputs) {
    const std::string stage = input.value("stage", "");
    const auto it = by_stage.find(stage);
    if (it == by_stage.end() || it->second->state != "done") {
      return run.stage + " consumed a " + stage + " run the clip no longer has";
    }
    const ReportRun& now = *it->second;
    if (now.finished_at.value_or(0) != input.value("finished_at", 0.0)) {
      return run.stage + " consumed an earlier " + stage + " run (parameters " +
             input.value("param_hash", "") + "), not the current one (" + now.param_hash + ")";
    }
  }
  return "";
}

}  // namespace

std::vector<UnsettledClip> FindUnsettled(const std::vector<ReportRun>& runs,
                                         const std::map<ClipId, std::string>& external_ids) {
  // The version's parameters: per stage, those of the newest finished run.
  std::map<std::string, std::pair<double, std::string>> newest;
  for (const ReportRun& r : runs) {
    if (r.state != "done" || !r.finished_at) continue;
    auto& [at, hash] = newest[r.stage];
    if (*r.finished_at >= at) at = *r.finished_at, hash = r.param_hash;
  }
  std::map<ClipId, std::map<std::string, const ReportRun*>> by_clip;
  for (const ReportRun& r : runs) by_clip[r.clip_id][r.stage] = &r;
  std::map<ClipId, std::string> why;
  for (const ReportRun& r : runs) {
    if (why.count(r.clip_id)) continue;  // the first reason is enough
    std::string reason;
    if (r.state == "pending" || r.state == "running") {
      reason = r.stage + " " + r.state;
      if (!r.requeued_by.empty()) reason += " (queued again after " + r.requeued_by + " changed)";
    } else if (r.state == "done") {
      reason = StaleInputs(r, by_clip[r.clip_id]);
      const std::string& current = newest[r.stage].second;
      if (reason.empty() && r.param_hash != current && r.verdict_source != kHumanVerdictSource) {
        reason = r.stage + " computed with parameters " + r.param_hash + ", the version's are " +
                 current;
      }
    }
    if (!reason.empty()) why[r.clip_id] = reason;
  }
  std::vector<UnsettledClip> out;
  for (const auto& [clip, reason] : why) {
    const auto it = external_ids.find(clip);
    out.push_back({clip, it == external_ids.end() ? "" : it->second, reason});
  }
  return out;
}

std::string NameClips(const std::vector<UnsettledClip>& clips, size_t max_named) {
  std::string text;
  for (size_t i = 0; i < clips.size() && i < max_named; ++i) {
    text += (i ? ", " : "") + std::string("clip ") + std::to_string(clips[i].clip_id);
    if (!clips[i].external_id.empty()) text += " " + clips[i].external_id;
    text += " (" + clips[i].why + ")";
  }
  if (clips.size() > max_named)
    text += " and " + std::to_string(clips.size() - max_named) + " more";
  return text;
}

}  // namespace doasido::dataset
