// The review server in-process on an ephemeral port, driven by an HTTP
// client: byte ranges, refusals (traversal, token, origin, host, remote
// bind), decisions flowing into the queue, and a preference study round.
#include "review/server.h"

#include <gtest/gtest.h>
#include <httplib.h>

#include <map>
#include <random>

#include "core/error.h"
#include "db/database.h"
#include "review/study.h"
#include "tests/test_util.h"

namespace doasido::review {
namespace {

using testing::TempDir;
using testing::WriteFile;

std::string RandomBytes(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::string s(n, '\0');
  for (auto& c : s) c = static_cast<char>(rng() & 0xff);
  return s;
}

// A database with three clips whose `interaction` stage flagged them, the
// pipeline continuing with out_of_frame.
class ReviewServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    video_bytes_ = RandomBytes(200003, 7);
    WriteFile(dir_ / "videos" / "clip.mp4", video_bytes_);
    Database db(dir_ / "d.db");
    db.SetPipeline({"interaction", "out_of_frame"});
    const VideoId video = db.UpsertVideo((dir_ / "videos" / "clip.mp4").string());
    for (int i = 0; i < 3; ++i) {
      ClipRecord c;
      c.video_id = video;
      c.external_id = "clip" + std::to_string(i);
      c.start_frame = i * 10;
      c.end_frame = i * 10 + 9;
      clips_.push_back(db.InsertClip(c).id);
    }
    for (int i = 0; i < 3; ++i) {
      const auto claim = db.ClaimNext("w", {"interaction"}, 60, 3);
      ASSERT_TRUE(claim);
      StageResult result;
      result.verdict = Verdict::kFlag;
      result.reason = "no_detections";
      result.measurements = {
          {"summary", {{"hand_frames", 0}, {"scores", Json::array({{{"name", "contact"},
                                                                    {"value", 0.1},
                                                                    {"rejects", "below"},
                                                                    {"reject", 0.05},
                                                                    {"flag", 0.2}}})}}}};
      ASSERT_TRUE(db.Complete(*claim, "w", "h", result, 0.1));
    }
    server_ = std::make_unique<ReviewServer>(dir_ / "d.db", ServeOptions{.port = 0});
    port_ = server_->Start();
    client_ = std::make_unique<httplib::Client>("127.0.0.1", port_);
  }

  httplib::Headers WriteHeaders() const {
    return {{"X-Doasido-Token", server_->token()}, {"Origin", server_->Origin()}};
  }

  httplib::Result Decide(const httplib::Headers& headers, ClipId clip, const std::string& decision,
                         const std::string& code = "no_interaction") {
    const Json body = {{"clip_id", clip}, {"stage", "interaction"}, {"decision", decision},
                       {"reason_code", code}, {"reason_text", "hands never touch it"},
                       {"reviewer", "ann"}};
    return client_->Post("/api/decision", headers, body.dump(), "application/json");
  }

  TempDir dir_;
  std::string video_bytes_;
  std::vector<ClipId> clips_;
  std::unique_ptr<ReviewServer> server_;
  int port_ = 0;
  std::unique_ptr<httplib::Client> client_;
};

TEST_F(ReviewServerTest, ServesTheVideoWithByteRanges) {
  const std::string url = "/video/" + std::to_string(clips_[0]);
  const size_t n = video_bytes_.size();
  auto whole = client_->Get(url);
  ASSERT_TRUE(whole);
  EXPECT_EQ(whole->status, 200);
  EXPECT_EQ(whole->body, video_bytes_);
  EXPECT_EQ(whole->get_header_value("Accept-Ranges"), "bytes");
  EXPECT_EQ(whole->get_header_value("Content-Type"), "video/mp4");
  EXPECT_EQ(whole->get_header_value("X-Content-Type-Options"), "nosniff");

  struct Case {
    std::string range;
    size_t first, last;
  };
  const std::vector<Case> partial = {{"bytes=100-199", 100, 199},
                                     {"bytes=0-0", 0, 0},
                                     {"bytes=" + std::to_string(n - 10) + "-", n - 10, n - 1},
                                     {"bytes=-500", n - 500, n - 1},
                                     {"bytes=150000-999999999", 150000, n - 1},
                                     {"bytes=-999999999", 0, n - 1}};
  for (const auto& c : partial) {
    auto r = client_->Get(url, {{"Range", c.range}});
    ASSERT_TRUE(r) << c.range;
    EXPECT_EQ(r->status, 206) << c.range;
    EXPECT_EQ(r->body, video_bytes_.substr(c.first, c.last - c.first + 1)) << c.range;
    EXPECT_EQ(r->get_header_value("Content-Range"),
              "bytes " + std::to_string(c.first) + "-" + std::to_string(c.last) + "/" +
                  std::to_string(n))
        << c.range;
  }
  for (const std::string& range :
       {"bytes=" + std::to_string(n) + "-", "bytes=" + std::to_string(n + 100) + "-" +
                                                std::to_string(n + 200),
        std::string("bytes=-0")}) {
    auto r = client_->Get(url, {{"Range", range}});
    ASSERT_TRUE(r) << range;
    EXPECT_EQ(r->status, 416) << range;
    EXPECT_EQ(r->get_header_value("Content-Range"), "bytes */" + std::to_string(n)) << range;
    EXPECT_TRUE(r->body.empty()) << range;
    EXPECT_EQ(r->get_header_value("X-Content-Type-Options"), "nosniff") << range;
  }
  auto reversed = client_->Get(url, {{"Range", "bytes=500-100"}});
  ASSERT_TRUE(reversed);
  EXPECT_EQ(reversed->status, 416);
  auto unknown = client_->Get("/video/999");
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->status, 404);
}

TEST_F(ReviewServerTest, RefusesPathTraversalAndServesNoPathFromTheUrl) {
  const std::string db_header = "SQLite format 3";
  for (const std::string target :
       {"/video/../d.db", "/video/%2e%2e/d.db", "/video/%2E%2E%2Fd.db", "/video/1/../../d.db",
        "/video/..%2f..%2fd.db", "/%2e%2e/%2e%2e/etc/passwd", "/video//etc/passwd",
        "/video/%2fetc%2fpasswd", "/media/trial/1/..%5c..%5cd.db", "/video/1%00.mp4",
        "/d.db", "/videos/clip.mp4", "/etc/passwd", "/video/abc", "/study/x/../../d.db",
        "/video/99999999999999999999999", "/media/trial/99999999999999999999999/left"}) {
    auto r = client_->Get(target);
    ASSERT_TRUE(r) << target;
    EXPECT_TRUE(r->status == 400 || r->status == 404) << target << " -> " << r->status;
    EXPECT_EQ(r->get_header_value("X-Content-Type-Options"), "nosniff") << target;
    EXPECT_EQ(r->body.find(db_header), std::string::npos) << target;
    EXPECT_EQ(r->body.find("root:"), std::string::npos) << target;
  }
}

TEST_F(ReviewServerTest, WritesNeedTheTokenAndTheSameOrigin) {
  const ClipId clip = clips_[0];
  const std::vector<std::pair<std::string, httplib::Headers>> refused = {
      {"no token", {{"Origin", server_->Origin()}}},
      {"wrong token", {{"X-Doasido-Token", std::string(64, '0')}, {"Origin", server_->Origin()}}},
      {"token in a cookie-less form post from elsewhere",
       {{"X-Doasido-Token", server_->token()}, {"Origin", "http://evil.example"}}},
      {"other port", {{"X-Doasido-Token", server_->token()},
                      {"Origin", "http://127.0.0.1:" + std::to_string(port_ + 1)}}},
      {"no origin and no referer", {{"X-Doasido-Token", server_->token()}}},
      {"foreign referer", {{"X-Doasido-Token", server_->token()},
                           {"Referer", "http://evil.example/" + server_->Origin()}}},
  };
  for (const auto& [what, headers] : refused) {
    auto r = Decide(headers, clip, "accept");
    ASSERT_TRUE(r) << what;
    EXPECT_EQ(r->status, 403) << what;
  }
  // A DNS-rebound page reaches the loopback port under a foreign Host name.
  auto rebound = client_->Get("/", {{"Host", "evil.example:" + std::to_string(port_)}});
  ASSERT_TRUE(rebound);
  EXPECT_EQ(rebound->status, 403);

  Database db(dir_ / "d.db");
  EXPECT_TRUE(db.ListReviews().empty());
  EXPECT_EQ(db.ListFlagged().size(), 3u);
  EXPECT_EQ(db.VerdictHistory(clip, "interaction").size(), 1u);
  EXPECT_TRUE(db.ListRuns({.stage = "out_of_frame"}).empty());

  // Same-origin by Referer alone is accepted (browsers omit Origin on some
  // requests), as is the right Origin.
  auto ok = Decide({{"X-Doasido-Token", server_->token()},
                    {"Referer", server_->Origin() + "/"}},
                   clip, "accept");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200) << ok->body;
}

// Ids are whole numbers in range: 14.7 is not clip 14, 1e30 does not
// overflow into some clip, and a body nested without end is refused before
// it is parsed. Nothing is recorded for any of them.
TEST_F(ReviewServerTest, RequestBodiesNeedWholeIdsAndAFewLevels) {
  const std::string first = std::to_string(clips_[0]);
  for (const std::string& id : std::vector<std::string>{first + ".7", "1e30", "-" + first, "0", "\"" + first + "\"",
                               "true", "null", "[" + first + "]", "18446744073709551615",
                               "9007199254740992"}) {
    const std::string body = R"({"clip_id": )" + id +
                             R"(, "stage": "interaction", "decision": "accept", "reviewer": "ann"})";
    auto r = client_->Post("/api/decision", WriteHeaders(), body, "application/json");
    ASSERT_TRUE(r) << id;
    EXPECT_EQ(r->status, 400) << id << " -> " << r->body;
    EXPECT_NE(r->body.find("clip_id"), std::string::npos) << id << " -> " << r->body;
  }
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  for (const std::string& body : std::vector<std::string>{
           deep, R"({"clip_id": )" + deep + "}", "[1, 2]", std::string(70000, ' ') + "{}"}) {
    auto r = client_->Post("/api/decision", WriteHeaders(), body, "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << r->body.substr(0, 200);
  }
  auto huge = client_->Get("/api/clip/99999999999999999999?stage=interaction");
  ASSERT_TRUE(huge);
  EXPECT_EQ(huge->status, 404) << huge->body;
  Database db(dir_ / "d.db");
  EXPECT_TRUE(db.ListReviews().empty());
  EXPECT_EQ(db.ListFlagged().size(), 3u);
  // The same request with a whole id is taken.
  EXPECT_EQ(Decide(WriteHeaders(), clips_[0], "accept", "")->status, 200);
}

TEST_F(ReviewServerTest, AcceptQueuesTheNextStageAndRejectIsAHumanVerdict) {
  auto accept = Decide(WriteHeaders(), clips_[0], "accept", "");
  ASSERT_TRUE(accept);
  ASSERT_EQ(accept->status, 200) << accept->body;
  auto reject = Decide(WriteHeaders(), clips_[1], "reject");
  ASSERT_TRUE(reject);
  ASSERT_EQ(reject->status, 200) << reject->body;
  EXPECT_EQ(Json::parse(reject->body).at("remaining"), 1);

  Database db(dir_ / "d.db");
  const auto next = db.ListRuns({.stage = "out_of_frame"});
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].clip_id, clips_[0]);
  EXPECT_EQ(next[0].state, "pending");

  const auto accepted = db.ListRuns({.stage = "interaction", .clip = clips_[0]});
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].verdict, "pass");
  const auto rejected = db.ListRuns({.stage = "interaction", .clip = clips_[1]});
  ASSERT_EQ(rejected.size(), 1u);
  EXPECT_EQ(rejected[0].verdict, "reject");
  EXPECT_EQ(rejected[0].reason, "no_interaction: hands never touch it");
  const auto history = db.VerdictHistory(clips_[1], "interaction");
  ASSERT_EQ(history.size(), 2u);
  EXPECT_EQ(history[0].source, "stage");
  EXPECT_EQ(history[1].source, "human");
  EXPECT_EQ(history[1].verdict, "reject");

  const auto reviews = db.ListReviews();
  ASSERT_EQ(reviews.size(), 2u);
  EXPECT_EQ(reviews[0].clip_id, clips_[0]);
  EXPECT_EQ(reviews[0].decision, "accept");
  EXPECT_EQ(reviews[1].clip_id, clips_[1]);
  EXPECT_EQ(reviews[1].decision, "reject");
  EXPECT_EQ(reviews[1].reviewer, "ann");
  const auto events = db.ListEvents({"review"}, 0);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].clip_id, clips_[1]);
  EXPECT_EQ(events[1].worker, "ann");
  EXPECT_EQ(events[1].detail.rfind("reject no_interaction", 0), 0u) << events[1].detail;

  // A decided clip is no longer waiting: a second decision is refused.
  auto again = Decide(WriteHeaders(), clips_[1], "accept");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 409);
  EXPECT_EQ(db.ListReviews().size(), 2u);
  auto queue = client_->Get("/api/queue");
  ASSERT_TRUE(queue);
  const Json items = Json::parse(queue->body).at("items");
  ASSERT_EQ(items.size(), 1u);
  EXPECT_EQ(items[0].at("clip_id"), clips_[2]);
}

TEST_F(ReviewServerTest, ThePageCarriesTheTokenUnderAStrictPolicy) {
  auto page = client_->Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find(server_->token()), std::string::npos);
  const std::string csp = page->get_header_value("Content-Security-Policy");
  EXPECT_NE(csp.find("default-src 'none'"), std::string::npos) << csp;
  const auto at = csp.find("'nonce-");
  ASSERT_NE(at, std::string::npos) << csp;
  const std::string nonce = csp.substr(at + 7, csp.find('\'', at + 7) - at - 7);
  EXPECT_EQ(nonce.size(), 32u);
  EXPECT_NE(page->body.find("<script nonce=\"" + nonce + "\">"), std::string::npos);
  EXPECT_EQ(csp.find("unsafe-inline"), std::string::npos);
  EXPECT_EQ(page->get_header_value("X-Content-Type-Options"), "nosniff");
  EXPECT_EQ(page->body.find("http://"), std::string::npos) << "no external assets";
  auto clip = client_->Get("/api/clip/" + std::to_string(clips_[1]) + "?stage=interaction");
  ASSERT_TRUE(clip);
  const Json c = Json::parse(clip->body);
  EXPECT_EQ(c.at("summary").at("scores").at(0).at("name"), "contact");
  EXPECT_EQ(c.at("reason"), "no_detections");
  EXPECT_EQ(c.at("start_frame"), 10);
}

TEST(ReviewServerBind, NonLoopbackNeedsTheExplicitFlag) {
  TempDir dir;
  { Database created(dir / "d.db"); }  // the server only opens an existing database
  EXPECT_TRUE(IsLoopbackHost("127.0.0.1"));
  EXPECT_TRUE(IsLoopbackHost("127.8.9.10"));
  EXPECT_TRUE(IsLoopbackHost("::1"));
  EXPECT_TRUE(IsLoopbackHost("[::1]"));
  EXPECT_TRUE(IsLoopbackHost("localhost"));
  EXPECT_FALSE(IsLoopbackHost("0.0.0.0"));
  EXPECT_FALSE(IsLoopbackHost("::"));
  EXPECT_FALSE(IsLoopbackHost("192.168.1.20"));
  EXPECT_FALSE(IsLoopbackHost("example.com"));
  for (const std::string host : {"0.0.0.0", "::", "192.168.1.20"}) {
    try {
      ReviewServer server(dir / "d.db", {.host = host, .port = 0});
      ADD_FAILURE() << host << " was accepted without --allow-remote";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "remote_bind") << host;
      EXPECT_NE(std::string(e.what()).find("--allow-remote"), std::string::npos);
    }
  }
  ReviewServer remote(dir / "d.db", {.host = "0.0.0.0", .port = 0, .allow_remote = true});
  EXPECT_GT(remote.Start(), 0);
  remote.Stop();
}

// ---- Preference study over HTTP ---------------------------------------------

TEST(ReviewStudy, ThreeRatersPerItemWithLoggedLayoutAndSummary) {
  TempDir dir;
  for (const char* name : {"src", "ours", "base"}) {
    for (int i = 0; i < 4; ++i) {
      WriteFile(dir / "media" / (std::string(name) + std::to_string(i) + ".mp4"),
                RandomBytes(1000 + i, static_cast<unsigned>(name[0] * 10 + i)));
    }
  }
  std::string csv = "item_id,source_video,a_video,b_video,a_label,b_label\n";
  for (int i = 0; i < 4; ++i) {
    const std::string n = std::to_string(i);
    csv += "item" + n + ",src" + n + ".mp4,ours" + n + ".mp4,base" + n + ".mp4,ours,fpose\n";
  }
  WriteFile(dir / "media" / "items.csv", csv);
  WriteFile(dir / "media" / "bad.csv", "item_id,source_video,a_video,b_video,a_label,b_label\n"
                                       "x,src0.mp4,missing.mp4,base0.mp4,ours,fpose\n");
  {
    Database db(dir / "d.db");
    try {
      CreateStudyFromCsv(db, "bad", dir / "media" / "bad.csv", 3, 1);
      ADD_FAILURE() << "a missing video was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.site().line, 2);
      EXPECT_EQ(e.site().field, "a_video");
      EXPECT_NE(e.site().file.find("bad.csv"), std::string::npos);
    }
    CreateStudyFromCsv(db, "track", dir / "media" / "items.csv", 3, 42);
    EXPECT_THROW(CreateStudyFromCsv(db, "track", dir / "media" / "items.csv", 3, 42), Error);
  }
  ReviewServer server(dir / "d.db", {.port = 0});
  httplib::Client client("127.0.0.1", server.Start());
  const httplib::Headers write = {{"X-Doasido-Token", server.token()},
                                  {"Origin", server.Origin()}};
  // Each rater prefers by a fixed rule on the item, expressed as a side.
  const std::map<std::string, std::vector<std::string>> wants = {
      {"r1", {"a", "a", "b", "tie"}}, {"r2", {"a", "a", "a", "tie"}},
      {"r3", {"a", "b", "a", "tie"}}};
  std::map<std::string, int> left_is_a_count;
  for (const auto& [rater, choices] : wants) {
    for (int round = 0; round < 5; ++round) {
      auto next = client.Get("/api/study/track/next?rater=" + rater);
      ASSERT_TRUE(next);
      ASSERT_EQ(next->status, 200) << next->body;
      const Json t = Json::parse(next->body);
      if (t.at("done").get<bool>()) {
        EXPECT_EQ(round, 4) << rater << " ran out early";
        break;
      }
      ASSERT_LT(round, 4) << rater << " got a fifth item";
      const std::string item = t.at("item_id");
      const int index = item.back() - '0';
      // The left video is A's file exactly when the trial put A on the left.
      auto left = client.Get(t.at("left_url").get<std::string>());
      ASSERT_TRUE(left);
      const bool left_is_a = left->body == testing::ReadFile(dir / "media" /
                                                             ("ours" + std::to_string(index) +
                                                              ".mp4"));
      EXPECT_EQ(left_is_a, LeftIsA(42, item, rater));
      left_is_a_count[rater] += left_is_a;
      const std::string want = choices[index];
      const std::string side = want == "tie" ? "tie"
                               : (want == "a") == left_is_a ? "left"
                                                             : "right";
      const Json body = {{"trial_id", t.at("trial_id")}, {"rater", rater}, {"choice", side}};
      auto r = client.Post("/api/study/track/answer", write, body.dump(), "application/json");
      ASSERT_TRUE(r);
      EXPECT_EQ(r->status, 200) << r->body;
      // Answering twice, or without the token, is refused.
      auto twice = client.Post("/api/study/track/answer", write, body.dump(), "application/json");
      EXPECT_EQ(twice->status, 409);
      auto forged = client.Post("/api/study/track/answer", {{"Origin", server.Origin()}},
                                body.dump(), "application/json");
      EXPECT_EQ(forged->status, 403);
    }
  }
  // Every item has its three raters: a fourth rater gets nothing.
  auto fourth = client.Get("/api/study/track/next?rater=r4");
  ASSERT_TRUE(fourth);
  EXPECT_TRUE(Json::parse(fourth->body).at("done").get<bool>());
  auto summary = client.Get("/api/study/track/summary");
  ASSERT_TRUE(summary);
  const Json s = Json::parse(summary->body);
  // Choices: A 7, B 2, tie 3 of 12; items unanimous: item0 (a) and item3 (tie).
  EXPECT_EQ(s.at("ratings"), 12);
  EXPECT_EQ(s.at("counts").at("a"), 7);
  EXPECT_EQ(s.at("counts").at("b"), 2);
  EXPECT_EQ(s.at("counts").at("tie"), 3);
  EXPECT_NEAR(s.at("win_rate_a").get<double>(), 7.0 / 9.0, 1e-12);
  EXPECT_NEAR(s.at("unanimous_share").get<double>(), 0.5, 1e-12);
  // Table rows (a, b, tie): (3,0,0) (2,1,0) (2,1,0) (0,0,3).
  const auto k = FleissKappa({{3, 0, 0}, {2, 1, 0}, {2, 1, 0}, {0, 0, 3}});
  EXPECT_NEAR(s.at("fleiss_kappa").at("kappa").get<double>(), k.kappa, 1e-12);
  // P_i = 1, 1/3, 1/3, 1 -> P_bar 2/3; p = (7, 2, 3)/12 -> P_e = 62/144.
  EXPECT_NEAR(k.P_bar, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(k.P_e, 62.0 / 144.0, 1e-12);
  // The layout is randomised, not constant, across the twelve trials.
  int total_left_a = 0;
  for (const auto& [rater, n] : left_is_a_count) total_left_a += n;
  EXPECT_GT(total_left_a, 0);
  EXPECT_LT(total_left_a, 12);
  auto page = client.Get("/study/track/summary");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("id=\"kappa\" data-value=\""), std::string::npos);
}

}  // namespace
}  // namespace doasido::review
