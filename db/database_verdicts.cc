// Database: replacing verdicts (re-thresholding, a person's decision).
#include "db/database.h"

#include <sqlite3.h>

#include "db/statement.h"

namespace doasido {

// ---- Verdicts ---------------------------------------------------------------

void Database::SetVerdict(ClipId clip, const std::string& stage, Verdict verdict,
                          const std::string& reason, const std::string& source) {
  Transaction tx(*this);
  Prepare("UPDATE stage_runs SET verdict = ?, reason = ? WHERE clip_id = ? AND stage = ?"
          " AND state = 'done'")
      .Bind(1, ToString(verdict))
      .Bind(2, reason)
      .Bind(3, clip)
      .Bind(4, stage)
      .Run();
  if (sqlite3_changes(db_) == 0) {
    throw Error("not_done", "stage '" + stage + "' has not finished for this clip",
                {.clip = std::to_string(clip), .field = "stage"});
  }
  Prepare("INSERT INTO verdicts (clip_id, stage, verdict, reason, source, created_at)"
          " VALUES (?,?,?,?,?,?)")
      .Bind(1, clip)
      .Bind(2, stage)
      .Bind(3, ToString(verdict))
      .Bind(4, reason)
      .Bind(5, source)
      .Bind(6, Now())
      .Run();
  if (verdict == Verdict::kPass) {
    Release(clip);
  } else {
    DropLaterStages(clip, stage);
  }
  LogEvent(clip, stage, "verdict", source, std::string(ToString(verdict)) + " " + reason);
  tx.Commit();
}

bool Database::StoreRedecision(ClipId clip, const std::string& stage,
                               const std::string& param_hash, const StageResult& result,
                               bool changed, std::int64_t* requeued) {
  Transaction tx(*this);
  auto& last = Prepare("SELECT source FROM verdicts WHERE clip_id = ? AND stage = ?"
                       " ORDER BY id DESC LIMIT 1");
  last.Bind(1, clip).Bind(2, stage);
  const bool human = last.Step() && last.Text(0) == kHumanVerdictSource;
  last.Reset();
  // A person's verdict stands; the run takes the new parameters so that the
  // worker does not run it again.
  auto& update = Prepare(human ? "UPDATE stage_runs SET param_hash = ? WHERE clip_id = ?"
                                 " AND stage = ? AND state = 'done'"
                               : "UPDATE stage_runs SET param_hash = ?, verdict = ?, reason = ?"
                                 " WHERE clip_id = ? AND stage = ? AND state = 'done'");
  update.Bind(1, param_hash);
  if (!human) update.Bind(2, ToString(result.verdict)).Bind(3, result.reason);
  update.Bind(human ? 2 : 4, clip).Bind(human ? 3 : 5, stage).Run();
  if (sqlite3_changes(db_) == 0 || human) {
    tx.Commit();
    return false;
  }
  const double now = Now();
  Prepare("UPDATE measurements SET param_hash = ?, data = ?, created_at = ?"
          " WHERE clip_id = ? AND stage = ?")
      .Bind(1, param_hash)
      .Bind(2, result.measurements.dump())
      .Bind(3, now)
      .Bind(4, clip)
      .Bind(5, stage)
      .Run();
  if (changed) {
    Prepare("INSERT INTO verdicts (clip_id, stage, verdict, reason, source, param_hash,"
            " created_at) VALUES (?,?,?,?,'rethreshold',?,?)")
        .Bind(1, clip)
        .Bind(2, stage)
        .Bind(3, ToString(result.verdict))
        .Bind(4, result.reason)
        .Bind(5, param_hash)
        .Bind(6, now)
        .Run();
    // The same mechanism as a changed or re-run stage: what follows runs
    // again on the new verdict (MoveOn drops it again when the clip stops).
    RequeueDownstream(clip, stage);
    MoveOn(clip, stage, result.verdict);
    if (requeued) {
      auto& n = Prepare("SELECT COUNT(*) FROM stage_runs WHERE clip_id = ? AND position > ?"
                        " AND state = 'pending'");
      n.Bind(1, clip).Bind(2, StagePosition(stage));
      *requeued = n.Step() ? n.Int(0) : 0;
      n.Reset();
    }
    LogEvent(clip, stage, "rethreshold", "",
             std::string(ToString(result.verdict)) + " " + result.reason);
  }
  tx.Commit();
  return true;
}

std::map<std::string, Json> Database::MeasurementsWhere(ClipId clip, const std::string& json_path,
                                                       const std::string& value) {
  auto& q = Prepare("SELECT stage, data FROM measurements WHERE clip_id = ?"
                    " AND json_valid(data) AND json_extract(data, ?) = ?");
  q.Bind(1, clip).Bind(2, json_path).Bind(3, value);
  std::map<std::string, Json> out;
  while (q.Step()) out[q.Text(0)] = Json::parse(q.Text(1), nullptr, false);
  q.Reset();
  return out;
}

}  // namespace doasido
