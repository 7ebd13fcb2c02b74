// The download stage end to end: clip lists that name URLs and YouTube ids,
// fetched from a local HTTP server the test runs (404s, a transfer cut in
// the middle, a server too slow to finish), and a stand-in for yt-dlp that
// exits with each documented failure.
#include <gtest/gtest.h>
#include <httplib.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <thread>

#include "db/database.h"
#include "ingest/download.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::ReadFile;
using testing::RunDoasido;
using testing::SharedData;
using testing::TempDir;
using testing::WriteFile;

// SHA-256 by coreutils, a reader independent of the stage's OpenSSL digest.
std::string Sha256sum(const std::filesystem::path& file) {
  const std::string command = "sha256sum '" + file.string() + "'";
  std::FILE* pipe = popen(command.c_str(), "r");
  char buffer[128] = {0};
  const size_t n = pipe ? std::fread(buffer, 1, 64, pipe) : 0;
  if (pipe) pclose(pipe);
  return std::string(buffer, n);
}

// A server on 127.0.0.1 with videos under /v/<name>: "missing*" answer 404,
// "cut*" closes the connection halfway on its first request, "slow*"
// trickles 64 bytes every 100 ms, everything else is served whole or by
// range. Counts requests, and the most whole-file answers being prepared
// at once.
class VideoServer {
 public:
  explicit VideoServer(std::map<std::string, std::string> files) : files_(std::move(files)) {
    server_.Get(R"(/v/(.+))", [this](const httplib::Request& req, httplib::Response& res) {
      Serve(req, res);
    });
    port_ = server_.bind_to_any_port("127.0.0.1");
    thread_ = std::thread([this] { server_.listen_after_bind(); });
    while (!server_.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ~VideoServer() {
    stop_ = true;
    server_.stop();
    thread_.join();
  }
  std::string Url(const std::string& name) const {
    return "http://127.0.0.1:" + std::to_string(port_) + "/v/" + name;
  }
  int Requests(const std::string& name) {
    std::lock_guard lock(mutex_);
    return requests_[name];
  }
  int TotalRequests() {
    std::lock_guard lock(mutex_);
    int n = 0;
    for (const auto& [name, count] : requests_) n += count;
    return n;
  }
  int MaxInFlight() const { return max_in_flight_; }

 private:
  // Counts an answer in preparation while it exists.
  struct InFlight {
    explicit InFlight(VideoServer* s) : server(s) {
      const int now = ++server->in_flight_;
      int seen = server->max_in_flight_;
      while (now > seen && !server->max_in_flight_.compare_exchange_weak(seen, now)) {
      }
    }
    ~InFlight() { --server->in_flight_; }
    VideoServer* server;
  };

  void Serve(const httplib::Request& req, httplib::Response& res) {
    const std::string name = req.matches[1];
    int count = 0;
    {
      std::lock_guard lock(mutex_);
      count = ++requests_[name];
    }
    const auto it = files_.find(name);
    if (name.rfind("missing", 0) == 0 || it == files_.end()) {
      res.status = 404;
      res.set_content("not here", "text/plain");
      return;
    }
    const std::string& body = it->second;
    if (name.rfind("slow", 0) == 0) {
      res.set_content_provider(body.size(), "video/mp4",
                               [this, &body](size_t offset, size_t, httplib::DataSink& sink) {
                                 if (stop_) return false;
                                 std::this_thread::sleep_for(std::chrono::milliseconds(100));
                                 return sink.write(body.data() + offset,
                                                   std::min<size_t>(64, body.size() - offset));
                               });
      return;
    }
    if (name.rfind("cut", 0) == 0 && count == 1) {
      // Announces the whole file, sends half, then drops the connection.
      const size_t half = body.size() / 2;
      res.set_content_provider(body.size(), "video/mp4",
                               [&body, half](size_t offset, size_t, httplib::DataSink& sink) {
                                 if (offset >= half) return false;
                                 return sink.write(body.data() + offset,
                                                   std::min<size_t>(16384, half - offset));
                               });
      return;
    }
    // Ranges answered here (httplib would slice them itself otherwise).
    const std::string range = req.get_header_value("Range");
    const_cast<httplib::Request&>(req).ranges.clear();
    size_t first = 0;
    if (range.rfind("bytes=", 0) == 0) {
      first = std::stoul(range.substr(6));
      res.status = 206;
      res.set_header("Content-Range", "bytes " + std::to_string(first) + "-" +
                                          std::to_string(body.size() - 1) + "/" +
                                          std::to_string(body.size()));
    }
    {
      // Two transfers allowed at once would overlap in this pause.
      InFlight flight(this);
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    res.set_content(body.substr(first), "video/mp4");
  }

  std::map<std::string, std::string> files_;
  httplib::Server server_;
  int port_ = 0;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::map<std::string, int> requests_;
  std::atomic<int> in_flight_{0}, max_in_flight_{0};
};

Json QueueList(const std::string& db, const std::string& state, const std::string& stage = "") {
  std::vector<std::string> args = {"queue", "list", "--db",  db,        "--state",
                                   state,   "--json", "--limit", "0"};
  if (!stage.empty()) args.insert(args.end(), {"--stage", stage});
  const auto r = RunDoasido(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return Json::parse(r.out);
}

TEST(Download, TwentyUrlsFromALocalServerDownloadResumeTimeOutAndFilter) {
  TempDir dir;
  const auto videos = SharedData() / "videos";
  const std::string a = ReadFile(videos / "bass_guitar.mp4");
  const std::string b = ReadFile(videos / "making_cake.mp4");
  std::map<std::string, std::string> files;
  std::vector<std::string> good;
  for (int i = 0; i < 13; ++i) {
    const std::string name = "good_" + std::to_string(i) + ".mp4";
    files[name] = i % 2 ? b : a;
    good.push_back(name);
  }
  files["cut.mp4"] = b;
  good.push_back("cut.mp4");
  files["slow.mp4"] = a;
  VideoServer server(files);

  // 20 URLs: 14 good (one cut mid-transfer), 5 missing, 1 too slow; good_0
  // is listed twice (two spans of one video).
  std::string list = "url,id,start_frame,end_frame\n";
  for (const auto& name : good) list += server.Url(name) + "," + name + ",0,29\n";
  list += server.Url("good_0.mp4") + ",good_0_again,30,59\n";
  for (int i = 0; i < 5; ++i) {
    list += server.Url("missing_" + std::to_string(i) + ".mp4") + ",missing_" +
            std::to_string(i) + ",0,29\n";
  }
  list += server.Url("slow.mp4") + ",slow,0,29\n";
  WriteFile(dir / "urls.csv", list);
  WriteFile(dir / "config.json", R"({"download": {"max_per_host": 1, "low_speed_time_s": 1,
      "low_speed_bytes_per_s": 20000, "retries": 1, "retry_backoff_s": 0.1},
      "probe": {"count_frames": false}})");
  const std::string db = (dir / "work" / "d.db").string();
  const std::string config = (dir / "config.json").string();

  ASSERT_EQ(RunDoasido({"init", "--db", db, "--pipeline", "filters"}).exit_code, 0);
  const auto ingest = RunDoasido({"ingest", "--db", db, (dir / "urls.csv").string()});
  ASSERT_EQ(ingest.exit_code, 0) << ingest.err;
  const auto work = RunDoasido({"worker", "--db", db, "--config", config, "--until-empty",
                                "--jobs", "2", "--max-attempts", "2", "--poll", "0.05"});
  ASSERT_EQ(work.exit_code, 0) << work.err;

  // Failures: each 404 named and tried once; the slow server named a timeout.
  std::map<std::string, Json> failed;
  for (const auto& r : QueueList(db, "failed")) failed[r["external_id"].get<std::string>()] = r;
  EXPECT_EQ(failed.size(), 6u);
  for (int i = 0; i < 5; ++i) {
    const std::string id = "missing_" + std::to_string(i);
    ASSERT_TRUE(failed.count(id)) << id;
    EXPECT_EQ(failed[id]["stage"], ingest::kDownloadStageName);
    EXPECT_EQ(failed[id]["error"].get<std::string>().rfind("http_not_found: HTTP 404", 0), 0u)
        << failed[id]["error"];
    EXPECT_EQ(failed[id]["attempts"], 1);
    EXPECT_EQ(server.Requests(id + ".mp4"), 1) << "a 404 is not retried";
  }
  ASSERT_TRUE(failed.count("slow"));
  EXPECT_EQ(failed["slow"]["error"].get<std::string>().rfind(ingest::kDownloadTimeout, 0), 0u)
      << failed["slow"]["error"];
  EXPECT_EQ(failed["slow"]["attempts"], 2);
  EXPECT_EQ(server.Requests("slow.mp4"), 4) << "2 attempts x (1 + 1 retry)";

  // Every good clip went through probe and every filter: nothing pending,
  // nothing else failed, probe passed them all.
  EXPECT_TRUE(QueueList(db, "pending").empty());
  const Json probed = QueueList(db, "done", "probe");
  EXPECT_EQ(probed.size(), good.size() + 1);
  for (const auto& r : probed) EXPECT_EQ(r["verdict"], "pass") << r;
  Database d(db);
  const auto pipeline = d.Pipeline();
  ASSERT_EQ(pipeline.front(), ingest::kDownloadStageName);
  ASSERT_EQ(pipeline[1], "probe");
  std::set<std::string> reached_end_or_rejected;  // or flagged
  for (const auto& r : QueueList(db, "done")) {
    if (r["stage"] == pipeline.back() || r["verdict"] != "pass") {
      reached_end_or_rejected.insert(r["external_id"].get<std::string>());
    }
  }
  EXPECT_EQ(reached_end_or_rejected.size(), good.size() + 1);

  // One download per video: good_0's two clips share a videos row and one
  // request; the cut transfer resumed with a range and checks out.
  EXPECT_EQ(server.Requests("good_0.mp4"), 1);
  EXPECT_EQ(d.CountVideos(), 20);
  EXPECT_EQ(d.CountDownloadedVideos(), 14);
  EXPECT_EQ(server.Requests("cut.mp4"), 2);
  std::optional<Database::VideoFile> cut;
  std::int64_t resumed_from = 0;
  for (const auto& c : d.ListClips()) {
    if (c.external_id == "cut.mp4") {
      cut = d.GetVideoFile(c.video_id);
      const auto m = d.GetMeasurements(c.id, ingest::kDownloadStageName);
      ASSERT_TRUE(m.has_value());
      resumed_from = (*m)["resumed_from"].get<std::int64_t>();
      EXPECT_GT(resumed_from, 0) << *m;
      EXPECT_LT((*m)["resumed_from"].get<std::int64_t>(), static_cast<std::int64_t>(b.size()));
    }
  }
  ASSERT_TRUE(cut.has_value());
  EXPECT_EQ(cut->url, server.Url("cut.mp4"));
  EXPECT_EQ(cut->size_bytes, static_cast<std::int64_t>(b.size()));
  EXPECT_EQ(cut->sha256, Sha256sum(videos / "making_cake.mp4"));
  EXPECT_EQ(Sha256sum(cut->local_path), cut->sha256);
  EXPECT_EQ(std::filesystem::path(cut->local_path).parent_path().parent_path(),
            dir / "work" / "media");
  EXPECT_LE(server.MaxInFlight(), 1) << "max_per_host 1 across two worker processes";

  // Run statistics: bytes of the 14 downloads, failures by reason.
  const auto report = RunDoasido({"report", "--db", db, "--out", (dir / "report").string(),
                                  "--no-thumbnails"});
  ASSERT_EQ(report.exit_code, 0) << report.err;
  EXPECT_NE(report.out.find("downloads: 14 fetched"), std::string::npos) << report.out;
  EXPECT_NE(report.out.find("6 failed (download_timeout 1, http_not_found 5)"), std::string::npos)
      << report.out;
  const Json downloads = Json::parse(ReadFile(dir / "report" / "report.json"))["downloads"];
  EXPECT_EQ(downloads["fetched"], 14);
  EXPECT_EQ(downloads["failed"], 6);
  EXPECT_EQ(downloads["failures_by_reason"]["http_not_found"], 5);
  EXPECT_EQ(downloads["failures_by_reason"][ingest::kDownloadTimeout], 1);
  // 7 x a and 6 x b whole, and the rest of the cut file after its resume.
  EXPECT_EQ(downloads["bytes"].get<std::int64_t>(),
            7 * static_cast<std::int64_t>(a.size()) + 7 * static_cast<std::int64_t>(b.size()) -
                resumed_from)
      << downloads;
  EXPECT_GT(downloads["bytes_per_s"].get<double>(), 0);

  // Running again downloads nothing: a second database in the same folder
  // (so the same media folder) finds every finished file.
  const int requests = server.TotalRequests();
  const std::string db2 = (dir / "work" / "again.db").string();
  ASSERT_EQ(RunDoasido({"init", "--db", db2, "--pipeline", ingest::kDownloadStageName}).exit_code,
            0);
  ASSERT_EQ(RunDoasido({"ingest", "--db", db2, (dir / "urls.csv").string()}).exit_code, 0);
  ASSERT_EQ(RunDoasido({"worker", "--db", db2, "--config", config, "--until-empty",
                        "--max-attempts", "1", "--poll", "0.05"})
                .exit_code,
            0);
  EXPECT_EQ(QueueList(db2, "done").size(), good.size() + 1);
  Database d2(db2);
  for (const auto& c : d2.ListClips()) {
    const auto m = d2.GetMeasurements(c.id, ingest::kDownloadStageName);
    if (!m) continue;
    // good_0_again's video was local by the time its run started.
    const std::string source = ingest::ReadDownloadSummary((*m)["summary"]).source;
    EXPECT_TRUE(source == "reused" || (c.external_id == "good_0_again" && source == "local"))
        << c.external_id << ": " << source;
    EXPECT_EQ(ingest::ReadDownloadSummary((*m)["summary"]).bytes, 0);
  }
  // Only the 404s and the slow URL (two tries) were asked for again.
  EXPECT_EQ(server.TotalRequests(), requests + 5 + 2);
}

// A stand-in for yt-dlp: copies a video for one id, and for the others
// exits with each documented failure (by exit status, or by yt-dlp's words).
TEST(Download, CommandTemplateFailuresAreNamedInTheFailedQueue) {
  TempDir dir;
  const auto video = SharedData() / "videos" / "bass_guitar.mp4";
  WriteFile(dir / "fake-yt-dlp.sh",
            "url=$1; out=$2; id=$3\n"
            "case $id in\n"
            "  okVideo0001) echo downloading; cp '" + video.string() + "' \"$out\" ;;\n"
            "  gone0000001) echo 'ERROR: gone' >&2; exit 10 ;;\n"
            "  ytUnavail01) echo \"ERROR: [youtube] $id: Video unavailable\" >&2; exit 1 ;;\n"
            "  geo00000001) echo 'ERROR: blocked' >&2; exit 11 ;;\n"
            "  rate0000001) echo 'ERROR: slow down' >&2; exit 12 ;;\n"
            "  *) echo 'first line'; echo 'ERROR: [youtube] no formats found' >&2; exit 3 ;;\n"
            "esac\n");
  WriteFile(dir / "config.json",
            "{\"download\": {\"command\": \"sh '" + (dir / "fake-yt-dlp.sh").string() +
                "' {url} {output} {id}\", \"retries\": 0}}");
  std::string list = "url,id\n";
  for (const std::string id :
       {"okVideo0001", "gone0000001", "ytUnavail01", "geo00000001", "rate0000001", "broken00001"}) {
    list += "https://www.youtube.com/watch?v=" + id + "," + id + "\n";
  }
  list += "https://youtu.be/okVideo0001,ok_short_url\n";
  WriteFile(dir / "ids.csv", list);
  const std::string db = (dir / "d.db").string();
  ASSERT_EQ(RunDoasido({"init", "--db", db, "--pipeline", "download,probe"}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", db, "--config", (dir / "config.json").string(),
                               (dir / "ids.csv").string(), "--max-attempts", "2"});
  ASSERT_EQ(run.exit_code, 0) << run.err;

  std::map<std::string, Json> failed;
  for (const auto& r : QueueList(db, "failed")) failed[r["external_id"].get<std::string>()] = r;
  const std::map<std::string, std::pair<std::string, int>> expected = {
      {"gone0000001", {"video_unavailable", 1}}, {"ytUnavail01", {"video_unavailable", 1}},
      {"geo00000001", {"geo_blocked", 1}},       {"rate0000001", {"rate_limited", 2}},
      {"broken00001", {"download_failed", 2}}};
  EXPECT_EQ(failed.size(), expected.size());
  for (const auto& [id, what] : expected) {
    ASSERT_TRUE(failed.count(id)) << id;
    const std::string error = failed[id]["error"].get<std::string>();
    EXPECT_EQ(error.rfind(what.first + ":", 0), 0u) << error;
    EXPECT_EQ(failed[id]["attempts"], what.second) << id;
  }
  EXPECT_NE(failed["broken00001"]["error"].get<std::string>().find("no formats found"),
            std::string::npos)
      << "download_failed carries the command's last lines";

  // Both URL forms of one YouTube id are one file, probed from disk.
  const Json probed = QueueList(db, "done", "probe");
  ASSERT_EQ(probed.size(), 2u);
  for (const auto& r : probed) EXPECT_EQ(r["verdict"], "pass") << r;
  EXPECT_TRUE(std::filesystem::exists(dir / "media" / "youtube" / "okVideo0001.mp4"));
  EXPECT_EQ(Sha256sum(dir / "media" / "youtube" / "okVideo0001.mp4"), Sha256sum(video));
}

TEST(Download, UrlListsOfIdsIngestAndNonListsAreRefusedWhole) {
  TempDir dir;
  const std::string db = (dir / "d.db").string();
  // WiLoR's whim layout: YouTube id -> metadata.
  WriteFile(dir / "whim.json", R"({"dQw4w9WgXcQ": {"resolution": [1280, 720], "fps": 30},
    "9bZkp7q19f0": {"resolution": [1920, 1080], "fps": 25},
    "kJQP7kiw5Fk": {"resolution": [640, 360], "fps": 29.97}})");
  const auto whim = RunDoasido({"ingest", "--db", db, "--json", (dir / "whim.json").string()});
  ASSERT_EQ(whim.exit_code, 0) << whim.err;
  const Json s = Json::parse(whim.out)[0];
  EXPECT_EQ(s["format"], "idmap");
  EXPECT_EQ(s["inserted"], 3);
  EXPECT_EQ(s["bad_rows"], 0);
  Database d(db);
  std::map<std::string, std::string> videos;
  std::map<ClipId, std::string> by_clip;
  for (const auto& c : d.ListClips(&by_clip)) {
    videos[c.external_id] = by_clip[c.id];
    if (c.external_id == "kJQP7kiw5Fk") {
      EXPECT_DOUBLE_EQ(c.metadata["fps"].get<double>(), 29.97);
    }
  }
  EXPECT_EQ(videos["dQw4w9WgXcQ"], "https://www.youtube.com/watch?v=dQw4w9WgXcQ");

  // 100DOH frame names of two videos absent from the video folder.
  WriteFile(dir / "frames.txt",
            "boardgame_v_abcdefghijk_frame000010\nboardgame_v_abcdefghijk_frame000040\n"
            "diy_v_ABCDEFGHIJ_frame000005\n");
  const auto names =
      RunDoasido({"ingest", "--db", db, "--json", (dir / "frames.txt").string(),
                  "--video-url-template", "https://www.youtube.com/watch?v={id}"});
  ASSERT_EQ(names.exit_code, 0) << names.err;
  const Json n = Json::parse(names.out)[0];
  EXPECT_EQ(n["format"], "framenames");
  EXPECT_EQ(n["inserted"], 2);
  EXPECT_EQ(d.CountVideos(), 5);
  by_clip.clear();
  for (const auto& c : d.ListClips(&by_clip)) videos[c.external_id] = by_clip[c.id];
  EXPECT_EQ(videos["boardgame_v_abcdefghijk"], "https://www.youtube.com/watch?v=abcdefghijk");

  // A VOC folder whose video is absent (one hand box on one frame).
  WriteFile(dir / "voc" / "Annotations" / "kitchen_v_Zz9-_a0b1c2_frame000120.xml",
            "<annotation><object><name>hand</name><bndbox><xmin>10</xmin><ymin>20</ymin>"
            "<xmax>50</xmax><ymax>70</ymax></bndbox><contactstate>3</contactstate>"
            "<handside>1</handside></object></annotation>");
  const auto voc = RunDoasido({"ingest", "--db", db, "--json", (dir / "voc").string(),
                               "--video-url-template", "https://www.youtube.com/watch?v={id}"});
  ASSERT_EQ(voc.exit_code, 0) << voc.err;
  EXPECT_EQ(Json::parse(voc.out)[0]["inserted"], 1);
  EXPECT_EQ(Json::parse(voc.out)[0]["detections"], 1);
  by_clip.clear();
  for (const auto& c : d.ListClips(&by_clip)) videos[c.external_id] = by_clip[c.id];
  EXPECT_EQ(videos["kitchen_v_Zz9-_a0b1c2"], "https://www.youtube.com/watch?v=Zz9-_a0b1c2");

  // Not clip lists: refused whole, saying what was expected.
  WriteFile(dir / "settings.json", R"({"threshold": 0.5, "name": "x"})");
  WriteFile(dir / "number.json", "42\n");
  WriteFile(dir / "words.txt", "hello\nworld\n");
  for (const std::string bad : {"settings.json", "number.json", "words.txt"}) {
    const auto r = RunDoasido({"ingest", "--db", db, (dir / bad).string()});
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_NE(r.err.find("not_a_clip_list"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("expected a clip list"), std::string::npos) << r.err;
    EXPECT_EQ(r.out.find("bad row"), std::string::npos) << r.out;
  }
  EXPECT_EQ(d.CountClips(), 6);

  // Without the download stage, probe says the URL was not downloaded (not
  // "no such file") and does not retry it.
  const std::string bare = (dir / "bare.db").string();
  ASSERT_EQ(RunDoasido({"init", "--db", bare, "--pipeline", "probe"}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", bare, (dir / "whim.json").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const Json failed = QueueList(bare, "failed");
  ASSERT_EQ(failed.size(), 3u);
  for (const auto& r : failed) {
    EXPECT_EQ(r["error"].get<std::string>().rfind("video_not_downloaded:", 0), 0u) << r;
    EXPECT_EQ(r["attempts"], 1);
  }
}

}  // namespace
}  // namespace doasido
