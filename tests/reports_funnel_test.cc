// The playbook funnel against ground truth: 500 synthetic clips with a known
// defect mix are driven through the real queue (ClaimNext / Complete /
// Fail / SetVerdict, as workers and reviewers do) by an oracle that rejects
// exactly the clips whose defect each filter exists to catch. The expected
// funnel is simulated independently from the defect list and the pipeline
// order; the report's counts, JSON and CSV must equal it exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "db/database.h"
#include "reports/report.h"
#include "reports/report_files.h"
#include "synth/generator.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using synth::DefectKind;
using testing::ReadCsv;
using testing::TempDir;

const std::vector<std::string> kPipeline = {"probe",         "filters_analyze", "interaction",
                                            "out_of_frame",  "shot_boundary",   "activity",
                                            "camera_motion"};
const char* kSources[] = {"internet", "egocentric", "generated"};
constexpr int kClips = 500;
// Clips whose filters_analyze run errors on every attempt.
const std::set<int> kFailing = {7, 250};
// Clips whose activity run is claimed by a worker that never finishes.
const std::set<int> kStuck = {49, 199};

// The filter each defect kind is meant to be caught by, with its reason.
std::pair<std::string, std::string> Catcher(DefectKind kind) {
  switch (kind) {
    case DefectKind::kCut:
    case DefectKind::kCrossFade:
    case DefectKind::kFadeBlack: return {"shot_boundary", "shot_boundary"};
    case DefectKind::kPan:
    case DefectKind::kShake:
    case DefectKind::kZoom: return {"camera_motion", "camera_motion"};
    case DefectKind::kStatic: return {"activity", "no_activity"};
    case DefectKind::kNoContact: return {"interaction", "no_interaction"};
    case DefectKind::kHandOut:
    case DefectKind::kObjectOut: return {"out_of_frame", "out_of_frame"};
    case DefectKind::kClean: return {"", ""};
  }
  return {"", ""};
}

struct Decision {
  Verdict verdict = Verdict::kPass;
  std::string reason;
};

// The ground-truth stage decision for clip `i` of defect `kind`. Besides
// rejecting what each filter is for, shakes are flagged (as the real
// camera-motion filter does for weak shakes), every 10th clean clip is
// flagged as camera_motion_unknown and every 3rd object_out clip is
// flagged by out_of_frame.
Decision Oracle(int i, DefectKind kind, const std::string& stage) {
  const auto [catcher, reason] = Catcher(kind);
  if (stage == catcher) {
    if (kind == DefectKind::kShake) return {Verdict::kFlag, "camera_motion"};
    if (kind == DefectKind::kObjectOut && i % 3 == 0) return {Verdict::kFlag, "out_of_frame"};
    return {Verdict::kReject, reason};
  }
  if (stage == "camera_motion" && kind == DefectKind::kClean && i % 10 == 3) {
    return {Verdict::kFlag, "camera_motion_unknown"};
  }
  if (stage == "shot_boundary" && kind == DefectKind::kClean && i % 4 == 1) {
    return {Verdict::kPass, "trimmed"};
  }
  return {Verdict::kPass, ""};
}

// What a reviewer decides for a flagged clip, if anyone reviewed it yet:
// flagged clean clips with i % 20 == 3 are accepted, flagged object_out
// clips with even i are rejected.
std::optional<Decision> Review(int i, DefectKind kind, const std::string& stage) {
  if (stage == "camera_motion" && kind == DefectKind::kClean && i % 20 == 3) {
    return Decision{Verdict::kPass, "reviewed"};
  }
  if (stage == "out_of_frame" && kind == DefectKind::kObjectOut && i % 2 == 0) {
    return Decision{Verdict::kReject, "out_of_frame"};
  }
  return std::nullopt;
}

// A score for each decision, so score distributions have known sides:
// camera_motion's translation_rate rejects above 0.5 and flags above 0.3;
// activity's motion rejects below 0.2.
Json Summary(const std::string& stage, const Decision& d, int i) {
  Json scores = Json::array();
  if (stage == "camera_motion") {
    const double v = d.verdict == Verdict::kReject ? 0.6 + 0.001 * (i % 50)
                     : d.verdict == Verdict::kFlag ? 0.4
                                                   : 0.002 * (i % 100);
    scores.push_back(
        {{"name", "translation_rate"}, {"value", v}, {"rejects", "above"}, {"reject", 0.5},
         {"flag", 0.3}});
  } else if (stage == "activity") {
    const double v = d.verdict == Verdict::kReject ? 0.05 : 0.5 + 0.001 * i;
    scores.push_back({{"name", "motion"}, {"value", v}, {"rejects", "below"}, {"reject", 0.2}});
  } else {
    return {{"frames", 30}};  // a summary without scores
  }
  return {{"scores", scores}};
}

double Duration(int i, const std::string& stage) {
  return 0.001 * (1 + (i * 7 + static_cast<int>(stage.size())) % 13);
}

struct Expected {
  std::map<std::string, reports::FunnelStage> stages;
  std::int64_t survivors = 0;
  std::map<std::string, std::map<std::string, std::int64_t>> by_source;  // source -> outcome
  std::map<std::string, std::vector<double>> durations;
  std::int64_t human = 0;
};

// Walks every clip down the pipeline with the same rules, without the
// database.
Expected Simulate(const std::vector<DefectKind>& defects) {
  Expected e;
  for (int i = 0; i < kClips; ++i) {
    std::string outcome = "survived";
    for (const auto& stage : kPipeline) {
      auto& s = e.stages[stage];
      s.stage = stage;
      ++s.entering;
      if (stage == "filters_analyze" && kFailing.count(i)) {
        ++s.failed;
        outcome = "failed";
        break;
      }
      if (stage == "activity" && kStuck.count(i)) {
        ++s.pending;
        outcome = "in_progress";
        break;
      }
      Decision d = Oracle(i, defects[i], stage);
      if (d.verdict == Verdict::kFlag) {
        if (auto r = Review(i, defects[i], stage)) {
          d = *r;
          ++s.human_by_verdict[ToString(d.verdict)];
        }
      }
      e.durations[stage].push_back(Duration(i, stage));
      if (d.verdict == Verdict::kPass) {
        ++s.passed;
        if (!d.reason.empty()) ++s.passed_by_reason[d.reason];
        continue;
      }
      if (d.verdict == Verdict::kReject) {
        ++s.rejected;
        ++s.rejected_by_reason[d.reason];
        outcome = "rejected";
      } else {
        ++s.flagged;
        ++s.flagged_by_reason[d.reason];
        outcome = "flagged";
      }
      break;
    }
    if (outcome == "survived") ++e.survivors;
    ++e.by_source[kSources[i % 3]][outcome];
  }
  return e;
}

// Builds the database by running the queue the way workers and reviewers do.
void RunQueue(Database& db, const std::vector<DefectKind>& defects) {
  db.SetPipeline(kPipeline);
  std::map<ClipId, int> index;
  {
    Database::Transaction tx(db);
    for (int i = 0; i < kClips; ++i) {
      char name[16];
      std::snprintf(name, sizeof name, "c%04d", i);
      ClipRecord clip;
      clip.video_id = db.UpsertVideo(std::string("/nonexistent/videos/") + name + ".mp4");
      clip.external_id = name;
      clip.start_frame = 0;
      clip.end_frame = 29;
      clip.source_list = "/lists/pool.csv";
      clip.metadata = {{"source", kSources[i % 3]}, {"defects", synth::DefectName(defects[i])}};
      const auto r = db.InsertClip(clip);
      ASSERT_TRUE(r.inserted);
      index[r.id] = i;
    }
    tx.Commit();
  }
  Database::Transaction tx(db);
  const std::string workers[] = {"w1", "w2"};
  int turn = 0;
  std::vector<std::pair<ClipId, std::string>> flagged;
  while (true) {
    const std::string& worker = workers[turn++ % 2];
    const auto claim = db.ClaimNext(worker, {}, 3600, 2);
    if (!claim) break;
    const int i = index.at(claim->clip_id);
    if (claim->stage == "filters_analyze" && kFailing.count(i)) {
      db.Fail(*claim, worker, "decode error at frame " + std::to_string(i), 2);
      continue;
    }
    if (claim->stage == "activity" && kStuck.count(i)) continue;  // never completes
    const Decision d = Oracle(i, defects[i], claim->stage);
    StageResult result;
    result.verdict = d.verdict;
    result.reason = d.reason;
    result.measurements = {{"summary", Summary(claim->stage, d, i)}};
    ASSERT_TRUE(db.Complete(*claim, worker, "hash", result, Duration(i, claim->stage)));
    if (d.verdict == Verdict::kFlag) flagged.emplace_back(claim->clip_id, claim->stage);
    // Reviews happen while the queue runs; an accepted clip goes on.
    if (flagged.size() >= 5 || d.verdict == Verdict::kFlag) {
      for (const auto& [clip, stage] : flagged) {
        if (auto r = Review(index.at(clip), defects[index.at(clip)], stage)) {
          db.SetVerdict(clip, stage, r->verdict, r->reason, "human");
        }
      }
      flagged.clear();
    }
  }
  tx.Commit();
}

class ReportsFunnel : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    defects_ = synth::AssignDefects(
        synth::ParseMix("clean=0.34,cut=0.06,fade=0.06,black=0.06,pan=0.06,zoom=0.06,shake=0.06,"
                        "static=0.08,no_contact=0.08,out_of_frame=0.07,object_out=0.07"),
        kClips, 42);
    db_ = new Database(*dir_ / "pool.db");
    RunQueue(*db_, defects_);
    reports::ReportOptions options;
    options.thumbnails = false;
    out_ = new reports::ReportOutput(reports::WriteReport(*db_, *dir_ / "report", options));
  }
  static void TearDownTestSuite() {
    delete out_;
    delete db_;
    delete dir_;
  }
  static TempDir* dir_;
  static Database* db_;
  static std::vector<DefectKind> defects_;
  static reports::ReportOutput* out_;
};
TempDir* ReportsFunnel::dir_ = nullptr;
Database* ReportsFunnel::db_ = nullptr;
std::vector<DefectKind> ReportsFunnel::defects_;
reports::ReportOutput* ReportsFunnel::out_ = nullptr;

TEST_F(ReportsFunnel, DefectMixIsWhatTheTestAssumes) {
  ASSERT_EQ(defects_.size(), static_cast<size_t>(kClips));
  std::map<DefectKind, int> n;
  for (auto k : defects_) ++n[k];
  EXPECT_EQ(n.size(), 11u);  // every kind is present
  EXPECT_EQ(n[DefectKind::kClean], 170);
}

TEST_F(ReportsFunnel, CountsEqualTheSimulatedFunnelPerStageAndReason) {
  const Expected e = Simulate(defects_);
  const auto& f = out_->data.funnel;
  EXPECT_EQ(f.pool, kClips);
  ASSERT_EQ(f.stages.size(), kPipeline.size());
  for (size_t k = 0; k < kPipeline.size(); ++k) {
    const auto& got = f.stages[k];
    const auto& want = e.stages.at(kPipeline[k]);
    SCOPED_TRACE(kPipeline[k]);
    EXPECT_EQ(got.stage, kPipeline[k]);
    EXPECT_EQ(got.entering, want.entering);
    EXPECT_EQ(got.passed, want.passed);
    EXPECT_EQ(got.rejected, want.rejected);
    EXPECT_EQ(got.flagged, want.flagged);
    EXPECT_EQ(got.failed, want.failed);
    EXPECT_EQ(got.pending, want.pending);
    EXPECT_EQ(got.rejected_by_reason, want.rejected_by_reason);
    EXPECT_EQ(got.flagged_by_reason, want.flagged_by_reason);
    EXPECT_EQ(got.passed_by_reason, want.passed_by_reason);
    EXPECT_EQ(got.human_by_verdict, want.human_by_verdict);
    if (k + 1 < kPipeline.size()) {
      EXPECT_EQ(got.passed, f.stages[k + 1].entering);
    }
  }
  EXPECT_EQ(f.survivors, e.survivors);
  EXPECT_GT(e.survivors, 100);
  // The defect list alone says how many each filter must remove.
  std::map<std::string, std::int64_t> caught;
  for (int i = 0; i < kClips; ++i) {
    if (kFailing.count(i)) continue;
    const auto [stage, reason] = Catcher(defects_[i]);
    if (stage.empty() || (kStuck.count(i) && (stage == "activity" || stage == "camera_motion"))) {
      continue;
    }
    const Decision d = Oracle(i, defects_[i], stage);
    auto r = d.verdict == Verdict::kFlag ? Review(i, defects_[i], stage) : std::nullopt;
    if (d.verdict == Verdict::kReject || (r && r->verdict == Verdict::kReject)) ++caught[stage];
  }
  for (const auto& s : f.stages) {
    EXPECT_EQ(s.rejected, caught[s.stage]) << s.stage;
  }
}

TEST_F(ReportsFunnel, JsonAndCsvCarryTheSameCounts) {
  const Expected e = Simulate(defects_);
  std::ifstream in(out_->json);
  const Json j = Json::parse(in);
  EXPECT_EQ(j["funnel"]["pool"], kClips);
  EXPECT_EQ(j["funnel"]["survivors"], e.survivors);
  ASSERT_EQ(j["funnel"]["stages"].size(), kPipeline.size());
  for (const auto& s : j["funnel"]["stages"]) {
    const auto& want = e.stages.at(s["stage"]);
    EXPECT_EQ(s["entering"], want.entering);
    EXPECT_EQ(s["passed"], want.passed);
    EXPECT_EQ(s["rejected"], want.rejected);
    EXPECT_EQ(s["flagged"], want.flagged);
    EXPECT_EQ(s["failed"], want.failed);
    EXPECT_EQ(s["pending"], want.pending);
    for (const auto& [reason, n] : want.rejected_by_reason) {
      EXPECT_EQ(s["rejected_by_reason"][reason], n);
    }
    EXPECT_DOUBLE_EQ(s["entering_pct"].get<double>(), 100.0 * want.entering / kClips);
  }
  const auto funnel = ReadCsv(*dir_ / "report" / "funnel.csv");
  ASSERT_EQ(funnel.size(), kPipeline.size() + 3);  // header, pool, stages, survivors
  EXPECT_EQ(funnel[1][0], "pool");
  EXPECT_EQ(std::stoll(funnel[1][2]), kClips);
  for (size_t k = 0; k < kPipeline.size(); ++k) {
    const auto& row = funnel[k + 2];
    const auto& want = e.stages.at(kPipeline[k]);
    EXPECT_EQ(row[1], kPipeline[k]);
    EXPECT_EQ(std::stoll(row[2]), want.entering);
    EXPECT_EQ(std::stoll(row[3]), want.passed);
    EXPECT_EQ(std::stoll(row[4]), want.rejected);
    EXPECT_EQ(std::stoll(row[5]), want.flagged);
    EXPECT_EQ(std::stoll(row[6]), want.failed);
    EXPECT_EQ(std::stoll(row[7]), want.pending);
  }
  EXPECT_EQ(funnel.back()[0], "survivors");
  EXPECT_EQ(std::stoll(funnel.back()[2]), e.survivors);
  // reasons.csv: one row per stage, verdict and reason.
  std::map<std::string, std::int64_t> csv_reasons;
  for (const auto& row : ReadCsv(*dir_ / "report" / "reasons.csv")) {
    if (row[0] == "stage") continue;
    csv_reasons[row[0] + "/" + row[1] + "/" + row[2]] = std::stoll(row[3]);
  }
  std::map<std::string, std::int64_t> want_reasons;
  for (const auto& [stage, s] : e.stages) {
    for (const auto& [r, n] : s.rejected_by_reason) want_reasons[stage + "/reject/" + r] = n;
    for (const auto& [r, n] : s.flagged_by_reason) want_reasons[stage + "/flag/" + r] = n;
  }
  EXPECT_EQ(csv_reasons, want_reasons);
}

TEST_F(ReportsFunnel, PerSourceOutcomesMatch) {
  const Expected e = Simulate(defects_);
  const auto& sources = out_->data.sources;
  auto it = std::find_if(sources.begin(), sources.end(),
                         [](const auto& b) { return b.key == "source"; });
  ASSERT_NE(it, sources.end());
  ASSERT_EQ(it->rows.size(), 3u);
  std::int64_t total = 0;
  for (const auto& row : it->rows) {
    const auto& want = e.by_source.at(row.value);
    auto get = [&](const char* k) { return want.count(k) ? want.at(k) : 0; };
    EXPECT_EQ(row.survived, get("survived")) << row.value;
    EXPECT_EQ(row.rejected, get("rejected")) << row.value;
    EXPECT_EQ(row.flagged, get("flagged")) << row.value;
    EXPECT_EQ(row.failed, get("failed")) << row.value;
    EXPECT_EQ(row.in_progress, get("in_progress")) << row.value;
    total += row.clips;
  }
  EXPECT_EQ(total, kClips);
  // sources.csv agrees.
  for (const auto& row : ReadCsv(*dir_ / "report" / "sources.csv")) {
    if (row[0] != "source") continue;
    const auto& want = e.by_source.at(row[1]);
    EXPECT_EQ(std::stoll(row[3]), want.count("survived") ? want.at("survived") : 0);
  }
}

TEST_F(ReportsFunnel, ScoreSidesMatchDecisions) {
  const Expected e = Simulate(defects_);
  std::map<std::string, const reports::StageScores*> by_stage;
  for (const auto& s : out_->data.scores) by_stage[s.stage] = &s;
  ASSERT_EQ(by_stage.size(), kPipeline.size());
  const auto& cm = *by_stage.at("camera_motion");
  ASSERT_EQ(cm.scores.size(), 1u);
  const auto& tr = cm.scores[0];
  const auto& cm_want = e.stages.at("camera_motion");
  const std::int64_t decided = cm_want.entering - cm_want.pending - cm_want.failed;
  EXPECT_EQ(static_cast<std::int64_t>(tr.values.size()), decided);
  // Stored scores are the stage's own: a reviewer's later accept does not
  // change which side of the threshold the score is on.
  std::int64_t flagged_by_stage = cm_want.flagged;
  for (const auto& [v, n] : cm_want.human_by_verdict) flagged_by_stage += n;
  EXPECT_EQ(tr.reject_side, cm_want.rejected);
  EXPECT_EQ(tr.flag_zone, flagged_by_stage);
  EXPECT_EQ(tr.pass_side, decided - cm_want.rejected - flagged_by_stage);
  EXPECT_DOUBLE_EQ(tr.reject, 0.5);
  ASSERT_TRUE(tr.flag.has_value());
  EXPECT_DOUBLE_EQ(*tr.flag, 0.3);
  std::int64_t binned = 0;
  for (auto c : tr.bins) binned += c;
  EXPECT_EQ(binned, decided);
  const auto& act = by_stage.at("activity")->scores.at(0);
  EXPECT_EQ(act.rejects, "below");
  EXPECT_EQ(act.reject_side, e.stages.at("activity").rejected);
  // Stages without scores say so.
  EXPECT_EQ(by_stage.at("probe")->with_scores, 0);
  EXPECT_EQ(by_stage.at("probe")->measured, kClips);
  const std::string html = testing::ReadFile(out_->html);
  EXPECT_NE(html.find("No thresholded scores recorded for probe"), std::string::npos);
  EXPECT_EQ(std::count(html.begin(), html.end(), '\0'), 0);
}

TEST_F(ReportsFunnel, RunStatisticsMatchTheQueue) {
  const Expected e = Simulate(defects_);
  for (const auto& s : out_->data.runs) {
    SCOPED_TRACE(s.stage);
    std::vector<double> d = e.durations.count(s.stage) ? e.durations.at(s.stage)
                                                       : std::vector<double>{};
    ASSERT_EQ(s.duration.count, static_cast<std::int64_t>(d.size()));
    if (d.empty()) continue;
    std::sort(d.begin(), d.end());
    double sum = 0;
    for (double x : d) sum += x;
    EXPECT_NEAR(s.duration.total_s, sum, 1e-9);
    EXPECT_NEAR(s.duration.mean_s, sum / d.size(), 1e-12);
    const size_t n = d.size();
    EXPECT_DOUBLE_EQ(s.duration.median_s, n % 2 ? d[n / 2] : (d[n / 2 - 1] + d[n / 2]) / 2);
    // Nearest rank: the smallest value with at least 95% of values <= it.
    double p95 = d.back();
    for (double x : d) {
      if (std::count_if(d.begin(), d.end(), [&](double y) { return y <= x; }) >= 0.95 * n) {
        p95 = x;
        break;
      }
    }
    EXPECT_DOUBLE_EQ(s.duration.p95_s, p95);
    std::int64_t claims = 0;
    for (const auto& [w, c] : s.claims_by_worker) claims += c;
    EXPECT_GE(claims, s.runs);
  }
  const auto& fa = *std::find_if(out_->data.runs.begin(), out_->data.runs.end(),
                                 [](const auto& s) { return s.stage == "filters_analyze"; });
  EXPECT_EQ(fa.failed, static_cast<std::int64_t>(kFailing.size()));
  EXPECT_EQ(fa.failed_attempts, 2 * static_cast<std::int64_t>(kFailing.size()));
  ASSERT_EQ(fa.failures.size(), kFailing.size());
  for (int i : kFailing) {
    EXPECT_EQ(fa.errors.at("decode error at frame " + std::to_string(i)), 2);
  }
  EXPECT_EQ(fa.claims_by_worker.size(), 2u);
}

}  // namespace
}  // namespace doasido

namespace doasido::reports {
namespace {

Database::ReportRun DoneRun(ClipId clip, const std::string& stage, int position,
                        const std::string& verdict) {
  Database::ReportRun r;
  r.clip_id = clip;
  r.stage = stage;
  r.position = position;
  r.state = "done";
  r.verdict = verdict;
  r.reason = verdict == "pass" ? "" : "why_" + stage;
  return r;
}

// Flags do not stop the filters: a clip counts by its first reject, else
// as flagged at its first flag while it waits for a person.
TEST(ReportsOutcomes, FirstRejectElseFirstFlag) {
  const std::vector<std::string> pipeline = {"a", "b", "c", "d"};
  const std::vector<Database::ReportRun> runs = {
      DoneRun(1, "a", 0, "flag"), DoneRun(1, "b", 1, "flag"),   DoneRun(1, "c", 2, "pass"),
      DoneRun(2, "a", 0, "flag"), DoneRun(2, "b", 1, "reject"),
      DoneRun(3, "a", 0, "pass"), DoneRun(3, "b", 1, "pass"),   DoneRun(3, "c", 2, "pass"),
      DoneRun(3, "d", 3, "pass"),
      DoneRun(4, "a", 0, "flag"), DoneRun(4, "b", 1, "pass"), DoneRun(4, "c", 2, "pass"),
      DoneRun(4, "d", 3, "pass")};
  const auto outcomes = ComputeOutcomes(pipeline, runs);
  EXPECT_EQ(outcomes.at(1).outcome, Outcome::kFlagged);
  EXPECT_EQ(outcomes.at(1).stage, "a");
  EXPECT_EQ(outcomes.at(1).reason, "why_a");
  EXPECT_EQ(outcomes.at(2).outcome, Outcome::kRejected);
  EXPECT_EQ(outcomes.at(2).stage, "b");
  EXPECT_EQ(outcomes.at(3).outcome, Outcome::kSurvived);
  // Through every stage with its flag still waiting: not a survivor.
  EXPECT_EQ(outcomes.at(4).outcome, Outcome::kFlagged);
  const Funnel funnel = ComputeFunnel(pipeline, runs, 4);
  EXPECT_EQ(funnel.stages[3].passed, 2);
  EXPECT_EQ(funnel.survivors, 1);
}

// A stage whose verdict left later-listed stages not_measured was taken
// first: the funnel lists it before them, counts their not_measured apart
// (neither passed nor rejected nor flagged), and the clip where it was
// rejected.
TEST(ReportsOutcomes, NotMeasuredIsCountedApartInEvidenceOrder) {
  const std::vector<std::string> pipeline = {"shot", "hand", "camera"};
  Database::ReportRun unmeasured = DoneRun(1, "hand", 1, "not_measured");
  unmeasured.reason = "camera";
  const std::vector<Database::ReportRun> runs = {
      DoneRun(1, "shot", 0, "pass"), unmeasured, DoneRun(1, "camera", 2, "reject"),
      DoneRun(2, "shot", 0, "pass"), DoneRun(2, "hand", 1, "reject"),
      DoneRun(3, "shot", 0, "pass"), DoneRun(3, "hand", 1, "pass"),
      DoneRun(3, "camera", 2, "pass")};
  std::vector<std::string> taken_first;
  EXPECT_EQ(FunnelOrder(pipeline, runs, &taken_first),
            (std::vector<std::string>{"shot", "camera", "hand"}));
  EXPECT_EQ(taken_first, std::vector<std::string>{"camera"});
  const Funnel funnel = ComputeFunnel(pipeline, runs, 3);
  ASSERT_EQ(funnel.stages.size(), 3u);
  const FunnelStage& hand = funnel.stages[2];
  EXPECT_EQ(hand.stage, "hand");
  EXPECT_EQ(hand.entering, 3);
  EXPECT_EQ(hand.not_measured, 1);
  EXPECT_EQ(hand.not_measured_by.at("camera"), 1);
  EXPECT_EQ(hand.passed, 1);
  EXPECT_EQ(hand.rejected, 1);
  EXPECT_EQ(hand.flagged, 0);
  EXPECT_EQ(funnel.stages[1].rejected_by_reason.at("why_camera"), 1);
  const auto outcomes = ComputeOutcomes(pipeline, runs);
  EXPECT_EQ(outcomes.at(1).outcome, Outcome::kRejected);
  EXPECT_EQ(outcomes.at(1).stage, "camera");
  EXPECT_EQ(funnel.survivors, 1);
  // Without not_measured runs: the pipeline's order.
  taken_first.clear();
  EXPECT_EQ(FunnelOrder(pipeline, {runs.begin() + 3, runs.end()}, &taken_first), pipeline);
  EXPECT_TRUE(taken_first.empty());
}

}  // namespace
}  // namespace doasido::reports
