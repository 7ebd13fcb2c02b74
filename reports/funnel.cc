#include "reports/funnel.h"

#include <algorithm>
#include <set>

namespace doasido::reports {
namespace {

std::string ReasonKey(const std::string& reason) {
  return reason.empty() ? kUnspecifiedReason : reason;
}

}  // namespace

const char* ToString(Outcome o) {
  switch (o) {
    case Outcome::kSurvived: return "survived";
    case Outcome::kRejected: return "rejected";
    case Outcome::kFlagged: return "flagged";
    case Outcome::kFailed: return "failed";
    case Outcome::kInProgress: return "in_progress";
  }
  return "?";
}

std::vector<std::string> FunnelOrder(const std::vector<std::string>& pipeline,
                                     const std::vector<Database::ReportRun>& runs,
                                     std::vector<std::string>* taken_first) {
  std::vector<std::string> order = pipeline;
  std::map<std::string, int> extra;  // stage -> smallest position
  std::map<std::string, std::set<std::string>> decided_before;  // stage -> earlier evidence
  for (const auto& r : runs) {
    if (r.state == "done" && r.verdict == ToString(Verdict::kNotMeasured) && !r.reason.empty()) {
      decided_before[r.stage].insert(r.reason);
    }
    if (std::find(pipeline.begin(), pipeline.end(), r.stage) != pipeline.end()) continue;
    auto it = extra.find(r.stage);
    if (it == extra.end() || r.position < it->second) extra[r.stage] = r.position;
  }
  std::vector<std::pair<int, std::string>> sorted;
  for (const auto& [stage, position] : extra) sorted.emplace_back(position, stage);
  std::sort(sorted.begin(), sorted.end());
  for (const auto& [position, stage] : sorted) order.push_back(stage);
  // Evidence order: a deciding stage goes just before the first stage it
  // left unmeasured.
  std::vector<std::string> out;
  const auto emitted = [&](const std::string& s) {
    return std::find(out.begin(), out.end(), s) != out.end();
  };
  for (const std::string& stage : order) {
    if (emitted(stage)) continue;
    for (const std::string& first : decided_before[stage]) {
      if (emitted(first) || std::find(order.begin(), order.end(), first) == order.end()) continue;
      out.push_back(first);
      if (taken_first) taken_first->push_back(first);
    }
    out.push_back(stage);
  }
  return out;
}

Funnel ComputeFunnel(const std::vector<std::string>& pipeline,
                     const std::vector<Database::ReportRun>& runs, std::int64_t clips) {
  Funnel funnel;
  funnel.pool = clips;
  const auto order = FunnelOrder(pipeline, runs, &funnel.taken_first);
  std::map<std::string, size_t> index;
  for (const auto& stage : order) {
    index[stage] = funnel.stages.size();
    funnel.stages.push_back({.stage = stage});
  }
  std::map<ClipId, bool> has_run;
  for (const auto& r : runs) {
    has_run[r.clip_id] = true;
    FunnelStage& s = funnel.stages[index.at(r.stage)];
    ++s.entering;
    if (r.state == "failed") {
      ++s.failed;
    } else if (r.state != "done" || r.verdict.empty()) {
      ++s.pending;
    } else {
      if (r.verdict_source == kHumanVerdictSource) ++s.human_by_verdict[r.verdict];
      if (r.verdict == "pass") {
        ++s.passed;
        if (!r.reason.empty()) ++s.passed_by_reason[r.reason];
      } else if (r.verdict == "reject") {
        ++s.rejected;
        ++s.rejected_by_reason[ReasonKey(r.reason)];
      } else if (r.verdict == ToString(Verdict::kNotMeasured)) {
        ++s.not_measured;
        ++s.not_measured_by[ReasonKey(r.reason)];
      } else {
        ++s.flagged;
        ++s.flagged_by_reason[ReasonKey(r.reason)];
      }
    }
  }
  // Passed the last stage with no flag still waiting (flags do not stop
  // the filters, so a flagged clip can pass the last one).
  for (const auto& [clip, o] : ComputeOutcomes(pipeline, runs)) {
    funnel.survivors += o.outcome == Outcome::kSurvived;
  }
  funnel.without_runs = clips - static_cast<std::int64_t>(has_run.size());
  return funnel;
}

std::map<ClipId, ClipOutcome> ComputeOutcomes(const std::vector<std::string>& pipeline,
                                              const std::vector<Database::ReportRun>& runs) {
  // Per clip: the furthest run, and the first flag (flags do not stop the
  // filters, so a clip flagged early may have passed or been rejected later).
  std::map<ClipId, const Database::ReportRun*> furthest, first_flag;
  for (const auto& r : runs) {
    // Stages run outside the pipeline do not move a clip along it.
    if (!pipeline.empty() &&
        std::find(pipeline.begin(), pipeline.end(), r.stage) == pipeline.end()) {
      continue;
    }
    auto& slot = furthest[r.clip_id];
    if (!slot || r.position > slot->position) slot = &r;
    if (r.state == "done" && r.verdict == "flag") {
      auto& flag = first_flag[r.clip_id];
      if (!flag || r.position < flag->position) flag = &r;
    }
  }
  std::map<ClipId, ClipOutcome> out;
  for (const auto& [clip, r] : furthest) {
    ClipOutcome o{.clip = clip, .stage = r->stage};
    o.human = r->verdict_source == kHumanVerdictSource;
    const auto flag = first_flag.find(clip);
    if (r->state == "failed") {
      o.outcome = Outcome::kFailed;
      o.reason = r->error;
    } else if (r->state != "done" || r->verdict.empty()) {
      o.outcome = Outcome::kInProgress;
    } else if (r->verdict == "reject") {
      o.outcome = Outcome::kRejected;  // its first reject: later stages did not run
      o.reason = ReasonKey(r->reason);
    } else if (flag != first_flag.end()) {
      o.outcome = Outcome::kFlagged;  // waits for a person at its first flag
      o.stage = flag->second->stage;
      o.human = flag->second->verdict_source == kHumanVerdictSource;
      o.reason = ReasonKey(flag->second->reason);
    } else {
      const bool last = !pipeline.empty() && r->stage == pipeline.back();
      o.outcome = last ? Outcome::kSurvived : Outcome::kInProgress;
    }
    out[clip] = o;
  }
  return out;
}

}  // namespace doasido::reports
