// Whether the runs a version would be cut from are settled: a version must
// not mix trajectories of old and new parameters, or a trajectory with a
// reconstruction it was not computed from (issue #42).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "db/database.h"

namespace doasido::dataset {

struct UnsettledClip {
  ClipId clip_id = 0;
  std::string external_id;
  std::string why;  // e.g. "retarget_kinematic pending (queued again after recon)"
};

// Clips of `runs` (Database::ReportRuns) whose runs are not settled:
//  - a run is pending or running;
//  - a done run consumed other upstream runs than the clip's current ones
//    (its recorded inputs name a run that finished at another time: the
//    upstream stage ran again since; re-thresholding, which changes a
//    run's parameter hash but not its result, does not count);
//  - a done run was computed with other parameters than the version's,
//    which are, per stage, those of its most recently finished run; a run
//    whose verdict a person gave is exempt (it is never run again for new
//    parameters).
// `external_ids` names the clips in the result.
std::vector<UnsettledClip> FindUnsettled(const std::vector<Database::ReportRun>& runs,
                                         const std::map<ClipId, std::string>& external_ids);

// "clip 3 (why), clip 7 (why), ... and N more", at most `max_named`.
std::string NameClips(const std::vector<UnsettledClip>& clips, size_t max_named = 10);

}  // namespace doasido::dataset
