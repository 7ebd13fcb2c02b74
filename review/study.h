// Preference studies (seed §4.2 human evaluation): each item pairs a source
// clip with two renderings, A and B (e.g. ours and a baseline). A rater sees
// the source and both renderings side by side, left/right randomised per
// trial, and picks the one that follows the source better, or a tie. Each
// item is judged by `raters_per_item` distinct raters.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "db/database.h"
#include "review/fleiss_kappa.h"

namespace doasido::review {

// Reads a study's items file: a CSV with a header naming the columns
// item_id, source_video, a_video, b_video, a_label, b_label (any order,
// extra columns ignored; quoted fields allowed). Video paths are relative
// to the CSV's folder unless absolute. Throws Error naming the file, line
// and field for a missing column, empty field, duplicate item id or a video
// file that does not exist.
std::vector<Database::StudyItemRecord> ReadStudyItems(const std::filesystem::path& csv);

// Reads `csv` and creates the study `name` in `db`. Returns its id.
std::int64_t CreateStudyFromCsv(Database& db, const std::string& name,
                                const std::filesystem::path& csv, int raters_per_item,
                                std::int64_t seed);

// The randomised layout of one trial: whether A is shown on the left. A
// pure function of the study seed, the item and the rater, so a layout can
// be re-derived from the log; it is also stored with the trial.
bool LeftIsA(std::int64_t seed, const std::string& item_id, const std::string& rater);

// The trial `rater` should see now: their open (unanswered) trial if its
// item still lacks ratings, else a new one for the item with the fewest
// trials among those the rater has not seen and that still lack raters
// (ties by item order). Another rater's open trial holds its slot for
// `abandon_after_s` seconds after it was shown; after that the slot is
// offered again (whoever answers first fills the item; later answers are
// refused). nullopt when nothing is left for this rater.
std::optional<Database::StudyTrialRecord> NextTrial(Database& db,
                                                    const Database::StudyRecord& study,
                                                    const std::string& rater,
                                                    double abandon_after_s = 1800);

struct StudyItemSummary {
  std::string item_id;
  int a = 0, b = 0, tie = 0;  // answered ratings per choice
  bool complete = false;      // has exactly raters_per_item answers
  bool unanimous = false;     // complete and all answers equal
};

struct StudySummary {
  std::string name;
  int raters_per_item = 0;
  int items = 0;
  int complete_items = 0;
  int ratings = 0;                 // answered trials
  int a = 0, b = 0, tie = 0;       // answered trials per choice
  double share_a = 0, share_b = 0, share_tie = 0;  // of all ratings
  std::optional<double> win_rate_a;                // a / (a + b); none without non-ties
  int unanimous_items = 0;
  std::optional<double> unanimous_share;           // of complete items
  // Over complete items, categories (a, b, tie); none with fewer than one
  // complete item or raters_per_item < 2.
  std::optional<FleissKappaResult> kappa;
  std::vector<std::string> a_labels, b_labels;     // distinct labels, in item order
  std::vector<StudyItemSummary> per_item;
};

StudySummary Summarize(const Database::StudyRecord& study,
                       const std::vector<Database::StudyItemRecord>& items,
                       const std::vector<Database::StudyTrialRecord>& trials);
StudySummary SummarizeStudy(Database& db, const std::string& name);  // throws for unknown name
Json ToJson(const StudySummary& summary);

}  // namespace doasido::review
