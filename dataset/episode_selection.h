// Which clips of a database become episodes of a new version, and why the
// others do not.
#pragma once

#include <vector>

#include "dataset/version.h"
#include "db/database.h"

namespace doasido::dataset {

struct EpisodeSelection {
  std::string trajectory_stage;
  std::vector<Episode> episodes;    // clip order; id, provenance and span set;
                                    // split, frames, fps, embodiment not yet
  std::vector<Exclusion> excluded;  // every other clip of the database
};

// The trajectory stage of a pipeline: "retarget" (dynamics-aware) when the
// pipeline has it, else "retarget_kinematic". Throws
// Error("no_trajectory_stage") when it has neither.
std::string TrajectoryStage(const std::vector<std::string>& pipeline);

// Walks every clip's runs in pipeline order. A clip becomes an episode when
// every stage before the trajectory stage passed and the trajectory stage's
// run is done with a verdict the selection takes: pass or flag (kAll), pass
// (kSuccess), pass given by a person in /verify (kVerified). Every other
// clip is excluded, naming the first run that stopped it.
EpisodeSelection SelectEpisodes(Database& db, Selection selection);

// The task of a clip, from its list row: "narration", else "verb object"
// (also "verb noun"), else "genre", else "manipulate the object".
std::string TaskOf(const Json& metadata);

}  // namespace doasido::dataset
