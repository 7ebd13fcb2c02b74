#include "review/study.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>

#include "core/csv.h"
#include "core/error.h"

namespace doasido::review {
namespace {

std::uint64_t Fnv1a(std::uint64_t h, const std::string& s) {
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

std::vector<Database::StudyItemRecord> ReadStudyItems(const std::filesystem::path& csv) {
  CsvReader reader = CsvReader::Open(csv, "study_items");
  const auto folder = std::filesystem::absolute(csv).parent_path();
  const std::vector<std::string> header = reader.Header();
  for (const std::string name :
       {"item_id", "a_video", "b_video", "a_label", "b_label", "source_video"}) {
    if (CsvColumn(header, name) == header.size()) {
      reader.Fail(reader.header_line(), name, "the header has no column '" + name + "'");
    }
  }
  std::vector<Database::StudyItemRecord> items;
  std::set<std::string> seen;
  CsvRecord record;
  while (reader.Next(record)) {
    if (!record.error.empty()) reader.Fail(record.line, "", record.error);
    if (record.Blank()) continue;
    auto get = [&](const std::string& name) {
      const size_t i = CsvColumn(header, name);
      const std::string value = i < record.fields.size() ? TrimCsvField(record.fields[i]) : "";
      if (value.empty()) reader.Fail(record.line, name, "empty field");
      return value;
    };
    auto video = [&](const std::string& name) {
      std::filesystem::path p = get(name);
      if (p.is_relative()) p = folder / p;
      p = p.lexically_normal();
      if (!std::filesystem::is_regular_file(p)) {
        reader.Fail(record.line, name, "video file not found: " + p.string());
      }
      return p.string();
    };
    Database::StudyItemRecord item;
    item.item_id = get("item_id");
    if (!seen.insert(item.item_id).second) {
      reader.Fail(record.line, "item_id", "duplicate item_id '" + item.item_id + "'");
    }
    item.source_video = video("source_video");
    item.a_video = video("a_video");
    item.b_video = video("b_video");
    item.a_label = get("a_label");
    item.b_label = get("b_label");
    items.push_back(std::move(item));
  }
  if (items.empty()) {
    throw Error("study_items", "the items file has no items", {.file = csv.string()});
  }
  return items;
}

std::int64_t CreateStudyFromCsv(Database& db, const std::string& name,
                                const std::filesystem::path& csv, int raters_per_item,
                                std::int64_t seed) {
  if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                             "0123456789_-.") != std::string::npos) {
    throw Error("study_name", "a study name uses only letters, digits, '_', '-' and '.'",
                {.field = "name"});
  }
  if (raters_per_item < 1) {
    throw Error("study_raters", "raters per item must be at least 1", {.field = "raters"});
  }
  Database::StudyRecord study;
  study.name = name;
  study.raters_per_item = raters_per_item;
  study.seed = seed;
  study.items_file = std::filesystem::absolute(csv).string();
  return db.CreateStudy(study, ReadStudyItems(csv));
}

bool LeftIsA(std::int64_t seed, const std::string& item_id, const std::string& rater) {
  std::uint64_t h = Fnv1a(1469598103934665603ull, item_id);
  h = Fnv1a(h ^ 0x1f, rater);
  return (SplitMix64(h ^ static_cast<std::uint64_t>(seed)) >> 63) != 0;
}

std::optional<Database::StudyTrialRecord> NextTrial(Database& db,
                                                    const Database::StudyRecord& study,
                                                    const std::string& rater,
                                                    double abandon_after_s) {
  Database::Transaction tx(db);
  const auto items = db.GetStudyItems(study.id);
  const auto trials = db.GetStudyTrials(study.id);
  const double now = Now();
  std::map<std::int64_t, int> answered, taken;
  for (const auto& t : trials) {
    if (!t.choice.empty()) {
      ++answered[t.item];
      ++taken[t.item];
    } else if (t.rater == rater || now - t.shown_at < abandon_after_s) {
      ++taken[t.item];
    }
  }
  std::set<std::int64_t> mine;
  for (const auto& t : trials) {
    if (t.rater != rater) continue;
    if (t.choice.empty() && answered[t.item] < study.raters_per_item) return t;
    mine.insert(t.item);
  }
  const Database::StudyItemRecord* best = nullptr;
  for (const auto& item : items) {
    if (mine.count(item.id) || taken[item.id] >= study.raters_per_item) continue;
    if (!best || taken[item.id] < taken[best->id]) best = &item;
  }
  if (!best) return std::nullopt;
  const std::int64_t id = db.InsertStudyTrial(best->id, rater, LeftIsA(study.seed,
                                                                      best->item_id, rater));
  auto trial = db.GetStudyTrial(id);
  tx.Commit();
  return trial;
}

StudySummary Summarize(const Database::StudyRecord& study,
                       const std::vector<Database::StudyItemRecord>& items,
                       const std::vector<Database::StudyTrialRecord>& trials) {
  StudySummary s;
  s.name = study.name;
  s.raters_per_item = study.raters_per_item;
  s.items = static_cast<int>(items.size());
  std::map<std::int64_t, size_t> index;
  for (const auto& item : items) {
    index[item.id] = s.per_item.size();
    s.per_item.push_back({item.item_id});
    if (std::find(s.a_labels.begin(), s.a_labels.end(), item.a_label) == s.a_labels.end()) {
      s.a_labels.push_back(item.a_label);
    }
    if (std::find(s.b_labels.begin(), s.b_labels.end(), item.b_label) == s.b_labels.end()) {
      s.b_labels.push_back(item.b_label);
    }
  }
  for (const auto& t : trials) {
    if (t.choice.empty() || !index.count(t.item)) continue;
    auto& row = s.per_item[index[t.item]];
    ++s.ratings;
    if (t.choice == "a") ++row.a, ++s.a;
    if (t.choice == "b") ++row.b, ++s.b;
    if (t.choice == "tie") ++row.tie, ++s.tie;
  }
  if (s.ratings > 0) {
    s.share_a = static_cast<double>(s.a) / s.ratings;
    s.share_b = static_cast<double>(s.b) / s.ratings;
    s.share_tie = static_cast<double>(s.tie) / s.ratings;
  }
  if (s.a + s.b > 0) s.win_rate_a = static_cast<double>(s.a) / (s.a + s.b);
  std::vector<std::vector<int>> table;
  for (auto& row : s.per_item) {
    const int n = row.a + row.b + row.tie;
    row.complete = n == study.raters_per_item;
    if (!row.complete) continue;
    ++s.complete_items;
    row.unanimous = row.a == n || row.b == n || row.tie == n;
    if (row.unanimous) ++s.unanimous_items;
    table.push_back({row.a, row.b, row.tie});
  }
  if (s.complete_items > 0) {
    s.unanimous_share = static_cast<double>(s.unanimous_items) / s.complete_items;
  }
  if (!table.empty() && study.raters_per_item >= 2) s.kappa = FleissKappa(table);
  return s;
}

StudySummary SummarizeStudy(Database& db, const std::string& name) {
  const auto study = db.GetStudy(name);
  if (!study) {
    throw Error("no_such_study", "no study named '" + name + "'",
                {.file = db.path().string(), .field = "name"});
  }
  return Summarize(*study, db.GetStudyItems(study->id), db.GetStudyTrials(study->id));
}

Json ToJson(const StudySummary& s) {
  auto opt = [](const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); };
  Json out = {{"name", s.name},
              {"raters_per_item", s.raters_per_item},
              {"items", s.items},
              {"complete_items", s.complete_items},
              {"ratings", s.ratings},
              {"counts", {{"a", s.a}, {"b", s.b}, {"tie", s.tie}}},
              {"share", {{"a", s.share_a}, {"b", s.share_b}, {"tie", s.share_tie}}},
              {"win_rate_a", opt(s.win_rate_a)},
              {"unanimous_items", s.unanimous_items},
              {"unanimous_share", opt(s.unanimous_share)},
              {"a_labels", s.a_labels},
              {"b_labels", s.b_labels}};
  if (s.kappa) {
    const auto& k = *s.kappa;
    out["fleiss_kappa"] = {{"kappa", k.defined ? Json(k.kappa) : Json(nullptr)},
                           {"P_bar", k.P_bar},
                           {"P_e", k.P_e},
                           {"subjects", k.subjects},
                           {"raters", k.raters},
                           {"categories", Json::array({"a", "b", "tie"})},
                           {"defined", k.defined},
                           {"note", k.note}};
  } else {
    out["fleiss_kappa"] = nullptr;
  }
  out["per_item"] = Json::array();
  for (const auto& row : s.per_item) {
    out["per_item"].push_back({{"item_id", row.item_id},
                               {"a", row.a},
                               {"b", row.b},
                               {"tie", row.tie},
                               {"complete", row.complete},
                               {"unanimous", row.unanimous}});
  }
  return out;
}

}  // namespace doasido::review
