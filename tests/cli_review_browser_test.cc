// The review web app and the playbook report in real headless Chromium
// (Debian's chromium + chromedriver, W3C WebDriver): play a clip, decide
// with the keyboard, run a three-rater preference study, render the report.
// Screenshots go to $DOASIDO_SHOTS_DIR when it is set.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <set>

#include "cli/review_reasons.h"
#include "db/database.h"
#include "review/fleiss_kappa.h"
#include "review/server.h"
#include "stages/stage_registry.h"
#include "tests/test_util.h"
#include "tests/webdriver.h"

namespace doasido {
namespace {

using testing::ChromeDriver;
using testing::RunDoasido;
using testing::TempDir;
using testing::WebDriverSession;

void MaybeScreenshot(WebDriverSession& session, const std::string& name) {
  if (const char* dir = std::getenv("DOASIDO_SHOTS_DIR")) {
    session.Screenshot(std::filesystem::path(dir) / (name + ".png"));
  }
}

class BrowserTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!testing::ChromiumAvailable()) {
      GTEST_SKIP() << "browser tests need Debian's chromium and chromium-driver "
                      "(/usr/bin/chromium, /usr/bin/chromedriver); not installed here";
    }
    driver_ = std::make_unique<ChromeDriver>(dir_ / "chromedriver.log");
  }

  // Four synthetic clips (160x120, 30 frames, H.264 from `doasido synth`).
  void Synth(const std::string& mix = "clean=1", int clips = 4) {
    const auto r = RunDoasido({"synth", "--out", (dir_ / "synth").string(), "--clips",
                               std::to_string(clips), "--frames", "30", "--width", "160",
                               "--height", "120", "--seed", "3", "--mix", mix, "--no-bundles"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }

  TempDir dir_;
  std::unique_ptr<ChromeDriver> driver_;
};

// The clips probed for real, then flagged by `interaction` with a score
// summary and one hand box per frame, as a filter stage would leave them,
// and passed by `out_of_frame` (a flag does not stop the filters; a clip
// waits for a person once they have all judged it).
std::vector<ClipId> FlagAll(Database& db) {
  auto probe = stages::MakeStage("probe", Json::object());
  while (auto claim = db.ClaimNext("test", {"probe"}, 60, 3)) {
    const StageResult result = probe->Run(db.LoadContext(claim->clip_id, "probe"));
    EXPECT_TRUE(db.Complete(*claim, "test", ParamHash(probe->Params()), result, 0.0));
  }
  std::vector<ClipId> flagged;
  while (auto claim = db.ClaimNext("test", {"interaction"}, 60, 3)) {
    std::vector<Detection> boxes;
    for (int f = 0; f < 30; ++f) {
      boxes.push_back({.frame = f, .kind = "hand", .x1 = 20, .y1 = 30, .x2 = 80, .y2 = 90,
                       .contact_state = 3, .hand_side = 1, .source = "test"});
    }
    db.AddDetections(claim->clip_id, boxes);
    StageResult result;
    result.verdict = Verdict::kFlag;
    result.reason = "no_detections";
    result.measurements = {
        {"summary",
         {{"contact_frames", 3},
          {"scores", Json::array({{{"name", "contact_share"}, {"value", 0.1},
                                   {"rejects", "below"}, {"reject", 0.05}, {"flag", 0.2}}})}}},
        {"shot", {{"boundaries", Json::array({12})},
                  {"trim", {{"start_frame", 0}, {"end_frame", 11}}}}}};
    EXPECT_TRUE(db.Complete(*claim, "test", "h", result, 0.0));
    flagged.push_back(claim->clip_id);
  }
  while (auto claim = db.ClaimNext("test", {"out_of_frame"}, 60, 3)) {
    EXPECT_TRUE(db.Complete(*claim, "test", "h", StageResult{}, 0.0));
  }
  return flagged;
}

TEST_F(BrowserTest, ReviewPagePlaysAClipAndTheKeyboardDecides) {
  Synth();
  const auto db_path = dir_ / "work" / "d.db";
  ASSERT_EQ(RunDoasido({"init", "--db", db_path.string(), "--pipeline",
                        "probe,interaction,out_of_frame,noop"}).exit_code, 0);
  const auto ingest = RunDoasido({"ingest", "--db", db_path.string(),
                                  (dir_ / "synth" / "clips.csv").string()});
  ASSERT_EQ(ingest.exit_code, 0) << ingest.err;
  Database db(db_path);
  // A fifth clip: the second half of the first video, to check playback
  // starts at the clip's span.
  ClipRecord late;
  late.video_id = db.GetClip(1).video_id;
  late.external_id = "late_half";
  late.start_frame = 15;
  late.end_frame = 29;
  ASSERT_TRUE(db.InsertClip(late).inserted);
  const auto flagged = FlagAll(db);
  ASSERT_EQ(flagged.size(), 5u);

  review::ServeOptions options{.port = 0, .reviewer = "ann"};
  cli::AddStageReasons(options);  // as `doasido review serve` does
  review::ReviewServer server(db_path, options);
  server.Start();
  WebDriverSession session(*driver_);
  session.Navigate(server.Origin() + "/");
  EXPECT_EQ(session.WaitFor("document.body.dataset.ready === '1' && "
                            "window.doasidoState.queue.length", "the queue"),
            5);
  // Every stage the clip went through is on the page with its verdict: the
  // flagging filter and the one after it.
  EXPECT_EQ(session.WaitFor(
                "(() => { const rows = [...document.querySelectorAll('#stages tr')]"
                ".map(r => r.textContent); return rows.length === 3 &&"
                " rows[1].includes('interaction') && rows[1].includes('flag no_detections') &&"
                " rows[1].includes('contact_share 0.1') && rows[2].includes('out_of_frame') &&"
                " rows[2].includes('pass') && rows.join('|'); })()",
                "every stage's verdict"),
            Json("probepass|interactionflag no_detectionscontact_share 0.1000 / 0.05000|"
                 "out_of_framepass"));

  // The late clip (last in the queue) starts playing at frame 15 = 0.5 s.
  session.PressKeys({"j", "j", "j", "j"});
  session.WaitFor("document.body.dataset.clipId === '5'", "the fifth clip");
  const Json start = session.WaitFor(
      "(() => { const v = document.getElementById('video');"
      " return v.readyState >= 1 && v.src.endsWith('/video/5') && !v.seeking &&"
      " v.currentTime > 0 && v.currentTime; })()",
      "the seek to the clip's start");
  EXPECT_NEAR(start.get<double>(), 0.5, 1.0 / 30);
  session.PressKeys({"k", "k", "k", "k"});
  session.WaitFor("document.body.dataset.clipId === '1'", "back to the first clip");

  // Play with the space bar; Debian's Chromium decodes the H.264 mp4 that
  // synth writes (OpenCV/FFmpeg avc1).
  session.WaitFor("document.getElementById('video').readyState >= 1", "video metadata");
  session.PressKeys({" "});
  const Json played = session.WaitFor(
      "(() => { const v = document.getElementById('video');"
      " return v.readyState >= 2 && v.played.length > 0 &&"
      " v.played.end(v.played.length - 1) - v.played.start(0) > 0.25 &&"
      " {t: v.currentTime, rs: v.readyState, w: v.videoWidth, err: v.error}; })()",
      "the clip to play", 20);
  EXPECT_EQ(played.at("w"), 160);
  EXPECT_TRUE(played.at("err").is_null());
  session.PressKeys({" "});  // pause

  // The hand box of the current frame is drawn on the overlay canvas: its
  // left edge is painted, its inside is not.
  const Json overlay = session.Execute(R"js(
    const v = document.getElementById('video'), c = document.getElementById('overlay');
    const s = Math.min(c.width / v.videoWidth, c.height / v.videoHeight);
    const ox = (c.width - v.videoWidth * s) / 2, oy = (c.height - v.videoHeight * s) / 2;
    const px = (x, y) => c.getContext('2d').getImageData(Math.round(x), Math.round(y), 1, 1).data;
    return {edge: px(ox + 20 * s, oy + 60 * s)[3], inside: px(ox + 50 * s, oy + 60 * s)[3],
            scores: document.querySelectorAll('#scores tr').length,
            cuts: document.querySelectorAll('#timeline .cut').length};
  )js");
  EXPECT_GT(overlay.at("edge").get<int>(), 0) << overlay.dump();
  EXPECT_EQ(overlay.at("inside"), 0) << overlay.dump();
  EXPECT_EQ(overlay.at("scores"), 2) << "header and one score row";
  EXPECT_EQ(overlay.at("cuts"), 1);
  MaybeScreenshot(session, "review_page");

  // j / k move through the queue.
  const std::string first = session.Execute("return document.body.dataset.clipId;");
  session.PressKeys({"j"});
  session.WaitFor("document.body.dataset.clipId !== '" + first + "'", "next clip");
  session.PressKeys({"k"});
  session.WaitFor("document.body.dataset.clipId === '" + first + "'", "previous clip");

  // a accepts the current clip; the next one becomes current; r rejects it.
  session.PressKeys({"a"});
  session.WaitFor("document.body.dataset.decisions === '1' && "
                  "window.doasidoState.clip && String(window.doasidoState.clip.clip_id) !== '" +
                      first + "'",
                  "the accept to be saved");
  const std::string second = session.Execute("return document.body.dataset.clipId;");
  session.PressKeys({"r"});
  session.WaitFor("document.body.dataset.decisions === '2'", "the reject to be saved");
  EXPECT_EQ(session.Execute("return window.doasidoState.queue.length;"), 3);
  MaybeScreenshot(session, "review_after_decisions");

  const auto reviews = db.ListReviews();
  ASSERT_EQ(reviews.size(), 2u);
  EXPECT_EQ(std::to_string(reviews[0].clip_id), first);
  EXPECT_EQ(reviews[0].decision, "accept");
  EXPECT_EQ(reviews[0].reviewer, "ann");
  EXPECT_EQ(std::to_string(reviews[1].clip_id), second);
  EXPECT_EQ(reviews[1].decision, "reject");
  EXPECT_EQ(reviews[1].reason, "no_interaction");
  // The accepted clip goes on past the filters; the rejected one lost its
  // later runs.
  const auto next = db.ListRuns({.stage = "noop"});
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(std::to_string(next[0].clip_id), first);
  EXPECT_EQ(next[0].state, "pending");
  const auto history = db.VerdictHistory(std::stoll(second), "interaction");
  ASSERT_FALSE(history.empty());
  EXPECT_EQ(history.back().source, "human");
  EXPECT_EQ(history.back().verdict, "reject");
  EXPECT_EQ(db.ListEvents({"review"}, 0).size(), 2u);

  // A clip flagged while the page is open appears after g (reload).
  db.SetVerdict(std::stoll(first), "interaction", Verdict::kFlag, "second_look", "test");
  session.PressKeys({"g"});
  session.WaitFor("window.doasidoState.queue.length === 4 && "
                  "window.doasidoState.queue.some(q => String(q.clip_id) === '" + first + "')",
                  "the reloaded queue");
}

TEST_F(BrowserTest, PreferenceStudyRoundWithThreeRaters) {
  Synth();
  std::string csv = "item_id,source_video,a_video,b_video,a_label,b_label\n";
  for (int i = 0; i < 3; ++i) {
    auto video = [](int k) { return "videos/s3c000" + std::to_string(k % 4) + ".mp4"; };
    csv += "item" + std::to_string(i) + "," + video(i) + "," + video(i + 1) + "," +
           video(i + 2) + ",ours,baseline\n";
  }
  testing::WriteFile(dir_ / "synth" / "items.csv", csv);
  const auto db_path = dir_ / "work" / "d.db";
  ASSERT_EQ(RunDoasido({"init", "--db", db_path.string(), "--pipeline", "probe"}).exit_code, 0);
  const auto created = RunDoasido({"review", "study", "create", "--db", db_path.string(),
                                   "--name", "track", "--items",
                                   (dir_ / "synth" / "items.csv").string()});
  ASSERT_EQ(created.exit_code, 0) << created.err;

  review::ReviewServer server(db_path, {.port = 0});
  server.Start();
  WebDriverSession session(*driver_);
  // Each rater answers by a fixed key rule; the sides pressed are recorded
  // per trial and must come back from the database mapped to a / b / tie.
  const std::map<std::string, std::vector<std::string>> keys = {
      {"r1", {"1", "1", "1"}},
      {"r2", {testing::keys::kArrowRight, "2", testing::keys::kArrowRight}},
      {"r3", {"3", "2", testing::keys::kArrowLeft}}};
  auto side_of = [](const std::string& key) {
    if (key == "1" || key == testing::keys::kArrowLeft) return "left";
    if (key == "2" || key == testing::keys::kArrowRight) return "right";
    return "tie";
  };
  std::map<std::int64_t, std::string> pressed;  // trial id -> side
  for (const auto& [rater, rule] : keys) {
    session.Navigate(server.Origin() + "/study/track?rater=" + rater);
    std::string last;
    for (int round = 0; round < 3; ++round) {
      const std::string trial =
          session.WaitFor("document.body.dataset.trial !== '" + last + "' && "
                          "document.body.dataset.trial", "a trial");
      if (rater == "r1" && round == 0) {
        session.WaitFor("['left', 'source', 'right'].every(id =>"
                        " document.getElementById(id).readyState >= 2)",
                        "all three videos to load", 20);
        MaybeScreenshot(session, "study_trial");
      }
      const std::string item = session.Execute("return document.body.dataset.item;");
      const std::string key = rule[static_cast<size_t>(item.back() - '0')];
      session.PressKeys({key});
      pressed[std::stoll(trial)] = side_of(key);
      last = trial;
      session.WaitFor("document.body.dataset.answered === '" + std::to_string(round + 1) + "'",
                      "the answer to be saved");
    }
    session.WaitFor("document.body.dataset.done === '1'", rater + " to finish");
  }

  // From the database: nine answered trials, three distinct raters per
  // item, sides as pressed and choices mapped through the logged layout.
  Database db(db_path);
  const auto study = db.GetStudy("track");
  ASSERT_TRUE(study);
  const auto items = db.GetStudyItems(study->id);
  const auto trials = db.GetStudyTrials(study->id);
  ASSERT_EQ(trials.size(), 9u);
  std::map<std::int64_t, std::set<std::string>> raters;
  std::map<std::int64_t, std::vector<int>> table;  // item -> (a, b, tie)
  int a = 0, b = 0, tie = 0;
  for (const auto& t : trials) {
    ASSERT_TRUE(pressed.count(t.id)) << t.id;
    EXPECT_EQ(t.side, pressed[t.id]);
    const std::string expect = t.side == "tie" ? "tie"
                               : (t.side == "left") == t.left_is_a ? "a"
                                                                    : "b";
    EXPECT_EQ(t.choice, expect);
    EXPECT_TRUE(t.answered_at.has_value());
    raters[t.item].insert(t.rater);
    auto& row = table[t.item];
    row.resize(3);
    ++row[t.choice == "a" ? 0 : t.choice == "b" ? 1 : 2];
    (t.choice == "a" ? a : t.choice == "b" ? b : tie) += 1;
  }
  for (const auto& item : items) EXPECT_EQ(raters[item.id].size(), 3u) << item.item_id;
  std::vector<std::vector<int>> counts;
  int unanimous = 0;
  for (const auto& [item, row] : table) {
    counts.push_back(row);
    unanimous += row[0] == 3 || row[1] == 3 || row[2] == 3;
  }
  const auto kappa = review::FleissKappa(counts);

  session.Navigate(server.Origin() + "/study/track/summary");
  auto shown = [&](const std::string& id) {
    const std::string v =
        session.Execute("return document.getElementById('" + id + "').dataset.value;");
    return v.empty() ? std::nan("") : std::stod(v);
  };
  EXPECT_NEAR(shown("ratings"), 9, 1e-9);
  EXPECT_NEAR(shown("share-a"), a / 9.0, 1e-6);
  EXPECT_NEAR(shown("share-b"), b / 9.0, 1e-6);
  EXPECT_NEAR(shown("share-tie"), tie / 9.0, 1e-6);
  ASSERT_GT(a + b, 0) << "the key rules give at least one non-tie";
  EXPECT_NEAR(shown("win-rate"), static_cast<double>(a) / (a + b), 1e-6);
  EXPECT_NEAR(shown("unanimous"), unanimous / 3.0, 1e-6);
  EXPECT_NEAR(shown("p-bar"), kappa.P_bar, 1e-6);
  EXPECT_NEAR(shown("p-e"), kappa.P_e, 1e-6);
  ASSERT_TRUE(kappa.defined);
  EXPECT_NEAR(shown("kappa"), kappa.kappa, 1e-6);
  const Json chart = session.Rect("#share-chart");
  EXPECT_GT(chart.at("width").get<double>(), 0);
  MaybeScreenshot(session, "study_summary");

  const auto cli = RunDoasido({"review", "study", "summary", "--db", db_path.string(), "--name",
                               "track", "--json"});
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  const Json s = Json::parse(cli.out);
  EXPECT_EQ(s.at("counts").at("a"), a);
  EXPECT_EQ(s.at("counts").at("b"), b);
  EXPECT_EQ(s.at("counts").at("tie"), tie);
  EXPECT_EQ(s.at("unanimous_items"), unanimous);
}

TEST_F(BrowserTest, ReportPageRendersItsCharts) {
  const auto help = RunDoasido({"report", "--help"});
  if (help.exit_code != 0) {
    GTEST_SKIP() << "`doasido report` is not built into this doasido yet: " << help.err;
  }
  Synth("clean=0.4,cut=0.2,pan=0.2,no_contact=0.2", 8);
  const auto db_path = dir_ / "work" / "d.db";
  ASSERT_EQ(RunDoasido({"init", "--db", db_path.string(), "--pipeline", "filters"}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", db_path.string(), "--jobs", "2",
                               (dir_ / "synth" / "clips.csv").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto report = RunDoasido({"report", "--db", db_path.string(), "--out",
                                  (dir_ / "report").string()});
  ASSERT_EQ(report.exit_code, 0) << report.err;
  const auto html = dir_ / "report" / "report.html";
  ASSERT_TRUE(std::filesystem::exists(html));

  WebDriverSession session(*driver_);
  session.Navigate("file://" + html.string());
  session.WaitFor("document.readyState === 'complete'", "the report to load");
  const Json boxes = session.Execute(R"js(
    const box = (e) => { const r = e.getBoundingClientRect(); return [r.width, r.height]; };
    const one = (sel) => { const e = document.querySelector(sel); return e ? box(e) : null; };
    return {chart: one('#funnel-chart'), table: one('#funnel-table'),
            scores: [...document.querySelectorAll('.score-chart')].map(box),
            chart_is_svg: !!document.querySelector('svg#funnel-chart')};
  )js");
  ASSERT_FALSE(boxes.at("chart").is_null()) << "no #funnel-chart";
  ASSERT_FALSE(boxes.at("table").is_null()) << "no #funnel-table";
  EXPECT_TRUE(boxes.at("chart_is_svg").get<bool>());
  for (const char* key : {"chart", "table"}) {
    EXPECT_GT(boxes.at(key).at(0).get<double>(), 0) << key;
    EXPECT_GT(boxes.at(key).at(1).get<double>(), 0) << key;
  }
  ASSERT_FALSE(boxes.at("scores").empty()) << "no .score-chart";
  for (const auto& s : boxes.at("scores")) {
    EXPECT_GT(s.at(0).get<double>(), 0);
    EXPECT_GT(s.at(1).get<double>(), 0);
  }
  MaybeScreenshot(session, "report_page");
}

}  // namespace
}  // namespace doasido
