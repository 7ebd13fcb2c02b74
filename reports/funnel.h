// The playbook funnel (seed §4.5): for each pipeline stage in order, how
// many clips entered it, how many it removed and why, how many wait for a
// person, failed or are still to run, and how many it passed on; and what
// finally happened to every clip.
//
// Counts are of stage runs as they stand now: a verdict a person gave in
// review (verdict source 'human') counts as what it decided, exactly like a
// stage's own verdict. A clip enters a stage when it has a run there (it
// was queued after passing the stage before, or its measurement there was
// not taken: not_measured).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "db/database.h"

namespace doasido::reports {

struct FunnelStage {
  std::string stage;
  std::int64_t entering = 0;
  std::int64_t passed = 0;    // verdict pass: passed on to the next stage
  std::int64_t rejected = 0;  // verdict reject: removed
  std::int64_t flagged = 0;   // verdict flag: waiting for review
  std::int64_t failed = 0;    // the stage errored out (attempts used up)
  std::int64_t pending = 0;   // queued or running, not decided yet
  // verdict not_measured: the stage's measurement did not run because an
  // earlier verdict in evidence order removed the clip (by that verdict's
  // stage); the clip moved on, neither passed nor judged here.
  std::int64_t not_measured = 0;
  std::map<std::string, std::int64_t> not_measured_by;
  // Reason code -> clips; an empty reason is counted as "unspecified".
  std::map<std::string, std::int64_t> rejected_by_reason;
  std::map<std::string, std::int64_t> flagged_by_reason;
  std::map<std::string, std::int64_t> passed_by_reason;  // e.g. "trimmed"
  // Current verdicts that a person gave in review, by verdict.
  std::map<std::string, std::int64_t> human_by_verdict;
};

struct Funnel {
  std::int64_t pool = 0;  // clips in the database
  // In the order the evidence was taken (FunnelOrder).
  std::vector<FunnelStage> stages;
  // Stages listed before the pipeline position of stages they left
  // unmeasured (empty: the pipeline's own order).
  std::vector<std::string> taken_first;
  std::int64_t survivors = 0;  // passed the last stage, no flag waiting for a person
  std::int64_t without_runs = 0;  // clips that never entered the first stage
};

// Where one clip stands: its first reject, else its first flag (waiting
// for a person), else its furthest stage run.
enum class Outcome { kSurvived, kRejected, kFlagged, kFailed, kInProgress };
const char* ToString(Outcome o);

struct ClipOutcome {
  ClipId clip = 0;
  Outcome outcome = Outcome::kInProgress;
  std::string stage;   // the stage of the furthest run (empty without runs)
  std::string reason;  // its reason code (rejected, flagged) or error text (failed)
  bool human = false;  // the deciding verdict was given by a person
};

inline constexpr char kUnspecifiedReason[] = "unspecified";

// The stages in funnel order, the order the evidence was taken: `pipeline`,
// then any other stage that has runs, by position; except that a stage
// whose verdict left another stage's runs not_measured (their reason names
// it) comes before that stage: its evidence was taken first (the cheap
// verdicts before the hand models, filters/deferred_hand_models.h). With
// `taken_first` (when given) the stages so moved.
std::vector<std::string> FunnelOrder(const std::vector<std::string>& pipeline,
                                     const std::vector<Database::ReportRun>& runs,
                                     std::vector<std::string>* taken_first = nullptr);

// The funnel over `runs` for a pool of `clips` clips.
Funnel ComputeFunnel(const std::vector<std::string>& pipeline,
                     const std::vector<Database::ReportRun>& runs, std::int64_t clips);

// The outcome of every clip that has runs, keyed by clip id. A clip whose
// furthest run passed is a survivor only when that run is of the last
// pipeline stage; otherwise it is in progress (its next stage is queued).
std::map<ClipId, ClipOutcome> ComputeOutcomes(const std::vector<std::string>& pipeline,
                                              const std::vector<Database::ReportRun>& runs);

}  // namespace doasido::reports
