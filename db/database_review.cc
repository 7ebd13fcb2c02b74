// Database members of the review module: the flagged-clip queue, people's
// decisions on it and preference studies (schema v2).
#include <sqlite3.h>

#include "db/database.h"
#include "db/statement.h"

namespace doasido {
namespace {

// A flagged clip waits for a person once every stage it went on to has
// finished and none rejected it (flags do not stop the filters, so a later
// filter may still reject it, and then nobody needs to look).
constexpr const char* kClipSettled =
    "NOT EXISTS (SELECT 1 FROM stage_runs o WHERE o.clip_id = r.clip_id"
    " AND (o.verdict = 'reject' OR o.state IN ('pending', 'running', 'failed')))";

}  // namespace

std::vector<Database::FlaggedRun> Database::ListFlagged() {
  auto& q = Prepare(
      "SELECT r.clip_id, IFNULL(c.external_id, ''), r.stage, IFNULL(r.reason, '')"
      " FROM stage_runs r JOIN clips c ON c.id = r.clip_id"
      " WHERE r.state = 'done' AND r.verdict = 'flag' AND " + std::string(kClipSettled) +
      " ORDER BY r.clip_id, r.position");
  std::vector<FlaggedRun> out;
  while (q.Step()) out.push_back({q.Int(0), q.Text(1), q.Text(2), q.Text(3)});
  q.Reset();
  return out;
}

std::int64_t Database::CountFlagged() {
  return QueryInt("SELECT COUNT(*) FROM stage_runs r WHERE state = 'done' AND verdict = 'flag'"
                  " AND " + std::string(kClipSettled));
}

void Database::RecordReview(ClipId clip, const std::string& stage, const std::string& reviewer,
                            bool accept, const std::string& reason) {
  Transaction tx(*this);
  auto& check = Prepare(
      "SELECT COUNT(*) FROM stage_runs WHERE clip_id = ? AND stage = ? AND state = 'done'"
      " AND verdict = 'flag'");
  check.Bind(1, clip).Bind(2, stage);
  const bool flagged = check.Step() && check.Int(0) > 0;
  check.Reset();
  if (!flagged) {
    throw Error("not_flagged", "stage '" + stage + "' of this clip is not waiting for review",
                {.clip = std::to_string(clip), .field = "stage"});
  }
  RecordHumanDecision(clip, stage, reviewer, accept, reason, reason,
                      std::string(accept ? "accept " : "reject ") + reason);
  tx.Commit();
}

void Database::RecordHumanDecision(ClipId clip, const std::string& stage,
                                   const std::string& reviewer, bool accept,
                                   const std::string& reason, const std::string& verdict_reason,
                                   const std::string& event_detail) {
  Prepare("INSERT INTO reviews (clip_id, stage, reviewer, decision, reason, created_at)"
          " VALUES (?,?,?,?,?,?)")
      .Bind(1, clip)
      .Bind(2, stage)
      .Bind(3, reviewer)
      .Bind(4, accept ? "accept" : "reject")
      .Bind(5, reason)
      .Bind(6, Now())
      .Run();
  SetVerdict(clip, stage, accept ? Verdict::kPass : Verdict::kReject, verdict_reason,
             kHumanVerdictSource);
  LogEvent(clip, stage, "review", reviewer, event_detail);
}

std::vector<Database::ReviewRow> Database::ListReviews() {
  auto& q = Prepare(
      "SELECT id, clip_id, stage, reviewer, decision, IFNULL(reason, ''), created_at,"
      " IFNULL(artifact_sha256, ''), IFNULL(param_hash, '') FROM reviews ORDER BY id");
  std::vector<ReviewRow> out;
  while (q.Step()) {
    out.push_back({q.Int(0), q.Int(1), q.Text(2), q.Text(3), q.Text(4), q.Text(5), q.Real(6),
                   q.Text(7), q.Text(8)});
  }
  q.Reset();
  return out;
}

std::vector<Database::VerdictRow> Database::VerdictHistory(ClipId clip, const std::string& stage) {
  auto& q = Prepare(
      "SELECT verdict, IFNULL(reason, ''), source, created_at FROM verdicts"
      " WHERE clip_id = ? AND stage = ? ORDER BY id");
  q.Bind(1, clip).Bind(2, stage);
  std::vector<VerdictRow> out;
  while (q.Step()) out.push_back({q.Text(0), q.Text(1), q.Text(2), q.Real(3)});
  q.Reset();
  return out;
}

// ---- Preference studies -------------------------------------------------------

std::int64_t Database::CreateStudy(const StudyRecord& study,
                                   const std::vector<StudyItemRecord>& items) {
  Transaction tx(*this);
  if (GetStudy(study.name)) {
    throw Error("study_exists", "a study named '" + study.name + "' already exists",
                {.file = path_.string(), .field = "name"});
  }
  Prepare("INSERT INTO studies (name, raters_per_item, seed, items_file, created_at)"
          " VALUES (?,?,?,?,?)")
      .Bind(1, study.name)
      .Bind(2, study.raters_per_item)
      .Bind(3, study.seed)
      .Bind(4, study.items_file.empty() ? std::string() : Store(study.items_file))
      .Bind(5, Now())
      .Run();
  const std::int64_t id = sqlite3_last_insert_rowid(db_);
  for (size_t i = 0; i < items.size(); ++i) {
    const auto& item = items[i];
    Prepare("INSERT INTO study_items (study_id, position, item_id, source_video, a_video,"
            " b_video, a_label, b_label) VALUES (?,?,?,?,?,?,?,?)")
        .Bind(1, id)
        .Bind(2, static_cast<std::int64_t>(i))
        .Bind(3, item.item_id)
        .Bind(4, Store(item.source_video))
        .Bind(5, Store(item.a_video))
        .Bind(6, Store(item.b_video))
        .Bind(7, item.a_label)
        .Bind(8, item.b_label)
        .Run();
  }
  LogEvent(std::nullopt, "", "study_created", "",
           study.name + " " + std::to_string(items.size()) + " items");
  tx.Commit();
  return id;
}

std::optional<Database::StudyRecord> Database::GetStudy(const std::string& name) {
  auto& q = Prepare(
      "SELECT id, name, raters_per_item, seed, IFNULL(items_file, ''), created_at FROM studies"
      " WHERE name = ?");
  q.Bind(1, name);
  std::optional<StudyRecord> out;
  if (q.Step()) {
    out = StudyRecord{q.Int(0), q.Text(1), static_cast<int>(q.Int(2)), q.Int(3), q.Text(4),
                      q.Real(5)};
    if (!out->items_file.empty()) out->items_file = Resolve(out->items_file).string();
  }
  q.Reset();
  return out;
}

namespace {

constexpr const char* kStudyItemColumns =
    "SELECT id, item_id, source_video, a_video, b_video, a_label, b_label FROM study_items";

// Every row of a prepared study_items query (kStudyItemColumns first).
std::vector<Database::StudyItemRecord> ReadStudyItems(const Database& db, db::Statement& q) {
  std::vector<Database::StudyItemRecord> out;
  while (q.Step()) {
    out.push_back({q.Int(0), q.Text(1), db.Resolve(q.Text(2)).string(),
                   db.Resolve(q.Text(3)).string(), db.Resolve(q.Text(4)).string(), q.Text(5),
                   q.Text(6)});
  }
  q.Reset();
  return out;
}

}  // namespace

std::vector<Database::StudyItemRecord> Database::GetStudyItems(std::int64_t study_id) {
  auto& q = Prepare(std::string(kStudyItemColumns) + " WHERE study_id = ? ORDER BY position");
  q.Bind(1, study_id);
  return ReadStudyItems(*this, q);
}

std::optional<Database::StudyItemRecord> Database::GetStudyItem(std::int64_t item) {
  auto& q = Prepare(std::string(kStudyItemColumns) + " WHERE id = ?");
  q.Bind(1, item);
  auto rows = ReadStudyItems(*this, q);
  if (rows.empty()) return std::nullopt;
  return rows.front();
}

namespace {

Database::StudyTrialRecord ReadTrial(db::Statement& q) {
  Database::StudyTrialRecord t;
  t.id = q.Int(0);
  t.item = q.Int(1);
  t.rater = q.Text(2);
  t.left_is_a = q.Int(3) != 0;
  t.side = q.IsNull(4) ? "" : q.Text(4);
  t.choice = q.IsNull(5) ? "" : q.Text(5);
  t.shown_at = q.Real(6);
  t.answered_at = q.OptReal(7);
  return t;
}

}  // namespace

std::vector<Database::StudyTrialRecord> Database::GetStudyTrials(std::int64_t study_id) {
  auto& q = Prepare(
      "SELECT t.id, t.item_id, t.rater, t.left_is_a, t.side, t.choice, t.shown_at,"
      " t.answered_at FROM study_trials t JOIN study_items i ON i.id = t.item_id"
      " WHERE i.study_id = ? ORDER BY t.id");
  q.Bind(1, study_id);
  std::vector<StudyTrialRecord> out;
  while (q.Step()) out.push_back(ReadTrial(q));
  q.Reset();
  return out;
}

std::optional<Database::StudyTrialRecord> Database::GetStudyTrial(std::int64_t trial_id) {
  auto& q = Prepare(
      "SELECT id, item_id, rater, left_is_a, side, choice, shown_at, answered_at"
      " FROM study_trials WHERE id = ?");
  q.Bind(1, trial_id);
  std::optional<StudyTrialRecord> out;
  if (q.Step()) out = ReadTrial(q);
  q.Reset();
  return out;
}

std::int64_t Database::InsertStudyTrial(std::int64_t item, const std::string& rater,
                                        bool left_is_a) {
  Transaction tx(*this);
  auto& exists = Prepare("SELECT COUNT(*) FROM study_trials WHERE item_id = ? AND rater = ?");
  exists.Bind(1, item).Bind(2, rater);
  const bool taken = exists.Step() && exists.Int(0) > 0;
  exists.Reset();
  if (taken) {
    throw Error("trial_exists", "rater '" + rater + "' already has a trial of this item",
                {.field = "rater"});
  }
  Prepare("INSERT INTO study_trials (item_id, rater, left_is_a, shown_at) VALUES (?,?,?,?)")
      .Bind(1, item)
      .Bind(2, rater)
      .Bind(3, left_is_a ? 1 : 0)
      .Bind(4, Now())
      .Run();
  const std::int64_t id = sqlite3_last_insert_rowid(db_);
  tx.Commit();
  return id;
}

bool Database::AnswerStudyTrial(std::int64_t trial_id, const std::string& rater,
                                const std::string& side) {
  if (side != "left" && side != "right" && side != "tie") {
    throw Error("bad_choice", "choice must be left, right or tie, not '" + side + "'",
                {.field = "choice"});
  }
  Transaction tx(*this);
  // The stored choice names the method, not the screen side: left maps to
  // a exactly when the trial showed a on the left.
  Prepare("UPDATE study_trials SET side = ?1,"
          " choice = CASE WHEN ?1 = 'tie' THEN 'tie'"
          "               WHEN (?1 = 'left') = (left_is_a = 1) THEN 'a' ELSE 'b' END,"
          " answered_at = ?2 WHERE id = ?3 AND rater = ?4 AND choice IS NULL"
          " AND (SELECT COUNT(*) FROM study_trials t WHERE t.item_id = study_trials.item_id"
          "      AND t.choice IS NOT NULL)"
          "   < (SELECT s.raters_per_item FROM studies s JOIN study_items i"
          "      ON i.study_id = s.id WHERE i.id = study_trials.item_id)")
      .Bind(1, side)
      .Bind(2, Now())
      .Bind(3, trial_id)
      .Bind(4, rater)
      .Run();
  const bool changed = sqlite3_changes(db_) > 0;
  if (changed) {
    const auto t = GetStudyTrial(trial_id);
    LogEvent(std::nullopt, "", "study_rating", rater,
             "trial " + std::to_string(trial_id) + " " + side + " -> " + (t ? t->choice : ""));
  }
  tx.Commit();
  return changed;
}

}  // namespace doasido
