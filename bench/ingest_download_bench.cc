// Download throughput and database overhead of the download stage.
//  1. Throughput: the same files from a local HTTP server (cpp-httplib on
//     127.0.0.1) fetched by DownloadVideo (libcurl, .part file, per-host
//     and per-file locks, SHA-256, sidecar) and, side by side, by one
//     `curl` process fetching them all (the peer: a bare transfer).
//  2. Database overhead per clip: claim, load context and complete a
//     download run whose result records the video file on the videos row,
//     against the same cycle for a run with empty measurements.
// Usage: ingest_download_bench [rounds]
#include <httplib.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "core/file_text.h"
#include "core/log.h"
#include "db/database.h"
#include "ingest/download.h"
#include "stages/probe_stage.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// Seconds per clip of claim + LoadContext + Complete for `clips` clips,
// with or without a video file in the result.
double DbCycle(const fs::path& dir, int clips, bool with_file) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  doasido::Database db(dir / "d.db");
  db.SetPipeline({doasido::ingest::kDownloadStageName, doasido::stages::kProbeStageName});
  {
    doasido::Database::Transaction tx(db);
    for (int i = 0; i < clips; ++i) {
      doasido::ClipRecord c;
      c.video_id = db.UpsertVideo("http://127.0.0.1/v/" + std::to_string(i) + ".mp4");
      c.external_id = "c" + std::to_string(i);
      db.InsertClip(c);
    }
    tx.Commit();
  }
  const auto t = Clock::now();
  while (auto claim = db.ClaimNext("bench", {doasido::ingest::kDownloadStageName}, 60, 3)) {
    const auto context = db.LoadContext(claim->clip_id, claim->stage);
    doasido::StageResult result;
    if (with_file) {
      result.measurements = {
          {"summary", {{"source", "http"}, {"bytes", 1000}, {"seconds", 0.1}}},
          {doasido::Database::kVideoFileKey,
           {{"path", (dir / "media" / (std::to_string(claim->clip_id) + ".mp4")).string()},
            {"size_bytes", 1000},
            {"sha256", std::string(64, 'a')}}}};
    }
    db.Complete(*claim, "bench", "hash", result, 0.1);
  }
  return Since(t) / clips;
}

}  // namespace

int main(int argc, char** argv) {
  doasido::InitLogging("warn");
  const int rounds = argc > 1 ? std::stoi(argv[1]) : 3;
  const fs::path dir =
      fs::temp_directory_path() / ("doasido-download-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path videos = fs::path(DOASIDO_SHARED_DATA) / "videos";
  std::vector<std::string> bodies;
  for (const char* name : {"02_cups.mp4", "03_blocks.mp4", "bedroom.mp4", "laptop_trackpad.mp4",
                           "pool_cleaning.mp4", "apple.mp4"}) {
    bodies.push_back(doasido::TryReadFile(videos / name).value_or(""));
  }
  const int files = 24;  // each body served under four names
  std::int64_t total = 0;
  for (int i = 0; i < files; ++i) total += static_cast<std::int64_t>(bodies[i % bodies.size()].size());

  httplib::Server server;
  server.Get(R"(/v/(\d+)\.mp4)", [&bodies](const httplib::Request& req, httplib::Response& res) {
    res.set_content(bodies[std::stoul(req.matches[1]) % bodies.size()], "video/mp4");
  });
  const int port = server.bind_to_any_port("127.0.0.1");
  std::thread thread([&server] { server.listen_after_bind(); });
  while (!server.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  auto url = [port](int i) {
    return "http://127.0.0.1:" + std::to_string(port) + "/v/" + std::to_string(i) + ".mp4";
  };

  double ours = 1e30, peer = 1e30;
  doasido::ingest::DownloadConfig config;
  int peer_rc = 0;
  for (int r = 0; r < rounds; ++r) {
    fs::remove_all(dir / "media");
    auto t = Clock::now();
    std::int64_t fetched = 0;
    for (int i = 0; i < files; ++i) {
      const auto out = doasido::ingest::DownloadVideo(url(i), dir / "media", dir / "logs", config);
      if (out.summary.source == "http") fetched += out.summary.bytes;
    }
    ours = std::min(ours, Since(t));
    if (fetched != total) {
      std::fprintf(stderr, "fetched %lld bytes, expected %lld\n", static_cast<long long>(fetched),
                   static_cast<long long>(total));
      return 1;
    }

    fs::remove_all(dir / "curl");
    fs::create_directories(dir / "curl");
    std::string cmd = "curl -s -f";
    for (int i = 0; i < files; ++i) {
      cmd += " -o '" + (dir / "curl" / (std::to_string(i) + ".mp4")).string() + "' '" + url(i) + "'";
    }
    t = Clock::now();
    peer_rc = std::system(cmd.c_str());
    peer = std::min(peer, Since(t));
  }
  server.stop();
  thread.join();

  const int clips = 2000;
  const double with_file = DbCycle(dir / "db1", clips, true);
  const double without = DbCycle(dir / "db2", clips, false);

  const double mb = static_cast<double>(total) / 1e6;
  std::printf("download of %d files, %.1f MB, from 127.0.0.1 (best of %d rounds)\n", files, mb,
              rounds);
  std::printf("  doasido DownloadVideo   %7.3f s  %8.1f MB/s  (transfer + SHA-256 + sidecar)\n",
              ours, mb / ours);
  if (peer_rc == 0) {
    std::printf("  curl (peer, 1 process)  %7.3f s  %8.1f MB/s\n", peer, mb / peer);
    std::printf("  ratio doasido/curl throughput: %.2f\n", peer / ours);
  } else {
    std::printf("  curl failed (exit %d): no peer figure\n", peer_rc);
  }
  std::printf("database per clip (%d clips): claim + context + complete\n", clips);
  std::printf("  with video file recorded  %7.1f us\n", with_file * 1e6);
  std::printf("  empty result (peer)       %7.1f us\n", without * 1e6);
  std::printf("  ratio: %.2f; extra %.1f us; the whole cycle is %.3f%% of one file's download\n",
              with_file / without, (with_file - without) * 1e6,
              100.0 * with_file / (ours / files));
  fs::remove_all(dir);
  return 0;
}
