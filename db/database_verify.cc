// Database members of trajectory verification (database.h): the queue of
// robot trajectories a person has not verified yet, and their decisions.
#include <sqlite3.h>

#include "db/database.h"
#include "db/statement.h"

namespace doasido {

std::vector<Database::TrajectoryRun> Database::ListTrajectoriesToVerify(
    const std::vector<std::string>& stages) {
  auto& q = Prepare(
      "SELECT r.clip_id, IFNULL(c.external_id, ''), r.stage, r.verdict, IFNULL(r.reason, '')"
      " FROM stage_runs r JOIN clips c ON c.id = r.clip_id"
      " WHERE r.stage = ? AND r.state = 'done' AND r.verdict IN ('pass', 'flag')"
      " AND IFNULL((SELECT v.source FROM verdicts v WHERE v.clip_id = r.clip_id"
      "             AND v.stage = r.stage ORDER BY v.id DESC LIMIT 1), '') <> ?"
      " ORDER BY r.clip_id");
  std::vector<TrajectoryRun> out;
  for (const std::string& stage : stages) {
    q.Bind(1, stage).Bind(2, kHumanVerdictSource);
    while (q.Step()) out.push_back({q.Int(0), q.Text(1), q.Text(2), q.Text(3), q.Text(4)});
    q.Reset();
  }
  return out;
}

void Database::RecordVerification(ClipId clip, const std::string& stage,
                                  const std::string& reviewer, bool accept,
                                  const std::string& reason,
                                  const std::string& trajectory_sha256) {
  Transaction tx(*this);
  auto& check = Prepare(
      "SELECT COUNT(*) FROM stage_runs WHERE clip_id = ? AND stage = ? AND state = 'done'"
      " AND verdict IN ('pass', 'flag')");
  check.Bind(1, clip).Bind(2, stage);
  const bool open = check.Step() && check.Int(0) > 0;
  check.Reset();
  if (!open) {
    throw Error("not_verifiable", "stage '" + stage + "' of this clip has no trajectory to verify",
                {.clip = std::to_string(clip), .field = "stage"});
  }
  RecordHumanDecision(clip, stage, reviewer, accept, reason, accept ? "" : reason,
                      std::string(accept ? "verify accept " : "verify reject ") + reason);
  Prepare("UPDATE reviews SET artifact_sha256 = ?, param_hash = (SELECT param_hash FROM stage_runs"
          " WHERE clip_id = ? AND stage = ?) WHERE id = (SELECT MAX(id) FROM reviews"
          " WHERE clip_id = ? AND stage = ?)")
      .Bind(1, trajectory_sha256)
      .Bind(2, clip)
      .Bind(3, stage)
      .Bind(4, clip)
      .Bind(5, stage)
      .Run();
  tx.Commit();
}

}  // namespace doasido
