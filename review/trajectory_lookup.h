// Where a clip's robot trajectory is: the output of the clip's run of its
// trajectory stage (retarget::TrajectoryStageOf, robot/trajectory/format.h)
// that the database records as done with verdict pass
// (Database::RecordedOutput). Used by the /verify page and by `doasido
// deploy --clip`; here rather than in robot/trajectory so that the
// trajectory format needs no database.
#pragma once

#include <optional>
#include <string>

#include "db/database.h"
#include "robot/trajectory/source.h"

namespace doasido::review {

// For a clip of `db`: the trajectory of the recorded run of the trajectory
// stage, when that run is done with verdict pass (or flag, when
// `allow_flag`: /verify shows those) and wrote trajectory.json; else
// std::nullopt with *why (when given) naming the run and what it is.
std::optional<retarget::TrajectoryFiles> FindTrajectoryFiles(Database& db, ClipId clip,
                                                   std::string* why = nullptr,
                                                   bool allow_flag = false);

}  // namespace doasido::review
