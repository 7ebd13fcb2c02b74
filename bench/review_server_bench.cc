// The review server's two hot paths, each against a peer measured in the
// same run:
//  * video bytes served as 256 KiB range requests (what a <video> element
//    does while seeking), vs httplib's own static file mount serving the
//    same file with the same ranges, and vs reading the file directly;
//  * decisions per second over HTTP (token/origin checks, JSON, review row,
//    human verdict, event, one transaction), vs Database::SetVerdict alone.
// Usage: review_server_bench [passes] [decisions]
#include <httplib.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include "core/log.h"
#include "db/database.h"
#include "review/server.h"
#include "filters/interaction.h"
#include "filters/out_of_frame.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

constexpr const char* kInteraction = doasido::filters::kInteractionStageName;

double Seconds(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Reads the whole file through `client` in `chunk`-byte ranges; returns MB/s.
double RangeMBps(httplib::Client& client, const std::string& url, std::uint64_t size,
                 int passes, std::uint64_t chunk) {
  std::uint64_t got = 0;
  const auto t0 = Clock::now();
  for (int p = 0; p < passes; ++p) {
    for (std::uint64_t first = 0; first < size; first += chunk) {
      const std::uint64_t last = std::min(size, first + chunk) - 1;
      auto r = client.Get(url, {{"Range", "bytes=" + std::to_string(first) + "-" +
                                              std::to_string(last)}});
      if (!r || r->status != 206) {
        std::fprintf(stderr, "range request failed on %s\n", url.c_str());
        std::exit(1);
      }
      got += r->body.size();
    }
  }
  return got / 1e6 / Seconds(t0);
}

double FileMBps(const fs::path& path, std::uint64_t size, int passes, std::uint64_t chunk) {
  std::vector<char> buffer(chunk);
  std::uint64_t got = 0;
  const auto t0 = Clock::now();
  for (int p = 0; p < passes; ++p) {
    std::ifstream in(path, std::ios::binary);
    for (std::uint64_t first = 0; first < size; first += chunk) {
      in.read(buffer.data(), static_cast<std::streamsize>(chunk));
      got += static_cast<std::uint64_t>(in.gcount());
    }
  }
  return got / 1e6 / Seconds(t0);
}

// n clips whose `interaction` run is done and flagged.
void FlagClips(doasido::Database& db, const std::string& video, int n, int offset) {
  doasido::Database::Transaction tx(db);
  const auto id = db.UpsertVideo(video);
  for (int i = 0; i < n; ++i) {
    doasido::ClipRecord clip;
    clip.video_id = id;
    clip.start_frame = offset + i;
    clip.end_frame = offset + i + 1;
    db.InsertClip(clip);
  }
  tx.Commit();
  doasido::StageResult flag;
  flag.verdict = doasido::Verdict::kFlag;
  flag.reason = "bench";
  while (auto claim = db.ClaimNext("bench", {kInteraction}, 60, 3)) {
    db.Complete(*claim, "bench", "h", flag, 0.0);
  }
}

}  // namespace

int main(int argc, char** argv) {
  doasido::InitLogging("warn");
  const int passes = argc > 1 ? std::atoi(argv[1]) : 20;
  const int decisions = argc > 2 ? std::atoi(argv[2]) : 300;
  const fs::path video = fs::path(DOASIDO_SHARED_DATA) / "videos" / "02_cups.mp4";
  const fs::path dir = fs::temp_directory_path() / ("review-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::uint64_t size = fs::file_size(video);
  const std::uint64_t chunk = 256 * 1024;

  {
    doasido::Database db(dir / "d.db");
    db.SetPipeline({kInteraction, doasido::filters::kOutOfFrameStageName});
    FlagClips(db, video.string(), 1 + 2 * decisions, 0);
  }
  doasido::review::ReviewServer server(dir / "d.db", {.port = 0});
  httplib::Client client("127.0.0.1", server.Start());
  client.set_keep_alive(true);
  client.set_tcp_nodelay(true);  // as browsers do

  httplib::Server peer;
  peer.set_mount_point("/files", video.parent_path().string());
  peer.set_tcp_nodelay(true);
  const int peer_port = peer.bind_to_any_port("127.0.0.1");
  std::thread peer_thread([&] { peer.listen_after_bind(); });
  while (!peer.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  httplib::Client peer_client("127.0.0.1", peer_port);
  peer_client.set_keep_alive(true);
  peer_client.set_tcp_nodelay(true);

  const double ours = RangeMBps(client, "/video/1", size, passes, chunk);
  const double mount = RangeMBps(peer_client, "/files/" + video.filename().string(), size,
                                 passes, chunk);
  const double file = FileMBps(video, size, passes, chunk);
  std::printf("video ranges (%s, %.1f MB, 256 KiB ranges, %d passes)\n",
              video.filename().c_str(), size / 1e6, passes);
  std::printf("  review server /video/<id>   %8.0f MB/s\n", ours);
  std::printf("  httplib static mount (peer) %8.0f MB/s   ratio %.2f\n", mount, ours / mount);
  std::printf("  ifstream reads (ceiling)    %8.0f MB/s   ratio %.2f\n", file, ours / file);
  peer.stop();
  peer_thread.join();

  const httplib::Headers headers = {{"X-Doasido-Token", server.token()},
                                    {"Origin", server.Origin()}};
  auto t0 = Clock::now();
  for (int i = 0; i < decisions; ++i) {
    const std::string body = "{\"clip_id\":" + std::to_string(2 + i) +
                             ",\"stage\":\"interaction\",\"decision\":\"accept\","
                             "\"reviewer\":\"bench\"}";
    auto r = client.Post("/api/decision", headers, body, "application/json");
    if (!r || r->status != 200) {
      std::fprintf(stderr, "decision failed: %s\n", r ? r->body.c_str() : "no response");
      return 1;
    }
  }
  const double http_rate = decisions / Seconds(t0);
  server.Stop();
  doasido::Database db(dir / "d.db");
  t0 = Clock::now();
  for (int i = 0; i < decisions; ++i) {
    db.SetVerdict(2 + decisions + i, kInteraction, doasido::Verdict::kPass, "bench", "bench");
  }
  const double direct_rate = decisions / Seconds(t0);
  std::printf("decisions (%d accepts, each queueing the next stage)\n", decisions);
  std::printf("  POST /api/decision          %8.0f /s\n", http_rate);
  std::printf("  Database::SetVerdict (peer) %8.0f /s   ratio %.2f\n", direct_rate,
              http_rate / direct_rate);
  fs::remove_all(dir);
  return 0;
}
