// Downloading a clip's video, what the `download` queue stage
// (stages/download_stage.h) does for a clip whose video is a URL: the video
// is fetched into the database's media folder before `probe` reads it.
//
//  - A clip whose video is a local file passes at once (nothing to do).
//  - http(s) URLs of hosts not in `command_hosts` are fetched with libcurl
//    (ingest/http_fetch.h): resumable through a .part file, size and
//    SHA-256 recorded, at most `max_per_host` transfers per host across
//    every worker process of the database (lock files in <media>/.locks).
//  - URLs of `command_hosts` (YouTube by default) go through `command`
//    (ingest/download_command.h documents the template, with yt-dlp as the
//    example, and how its failures are named).
//  - Transient failures (timeouts, interrupted transfers, 5xx, 429,
//    rate_limited, download_failed) are tried again within the run
//    `retries` times, waiting retry_backoff_s, then twice that, ...; a
//    failure a retry cannot fix (404, video_unavailable, geo_blocked) is a
//    permanent error (core/error_codes.h), which the worker fails at once.
//  - Files land in <media>/<host>/: http as <16 hex of the URL>-<name>,
//    command downloads as <video id>.mp4, each with a <file>.json sidecar
//    written after it is complete ({url, size_bytes, sha256}). Many clips
//    of one video share one videos row; whichever clip comes first
//    downloads, the others find the finished file (a per-file lock keeps
//    two workers from fetching it twice at once).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/config.h"

namespace doasido::ingest {

// The `download` stage's name (its queue name, config section and artifact
// folder), here so that `report` reads its summaries without the stages.
inline constexpr const char* kDownloadStageName = "download";

// Error codes of the stage (besides those of http_fetch.h).
inline constexpr const char* kRateLimited = "rate_limited";
inline constexpr const char* kDownloadFailed = "download_failed";
inline constexpr const char* kDownloadTimeout = "download_timeout";

struct DownloadConfig {
  // Where videos go; empty: <database folder>/media.
  std::string media_dir;
  int max_per_host = 4;
  // libcurl's connect timeout, and its low-speed abort: fewer than
  // low_speed_bytes_per_s for low_speed_time_s (whole seconds) is a
  // download_timeout. total_timeout_s > 0 also caps a whole transfer.
  double connect_timeout_s = 15;
  double low_speed_time_s = 30;
  double low_speed_bytes_per_s = 1024;
  double total_timeout_s = 0;
  int retries = 3;
  double retry_backoff_s = 2;
  // Site downloads (see download_command.h); empty command: URLs of
  // command_hosts fail with download_failed naming the missing setting.
  std::string command;
  std::vector<std::string> command_hosts = {"youtube.com", "www.youtube.com", "m.youtube.com",
                                            "youtu.be", "vimeo.com", "www.vimeo.com"};
  std::string format = "bv*[height<={max_height}][ext=mp4]+ba[ext=m4a]/b[height<={max_height}]";
  int max_height = 720;
  std::string user_agent = "doasido";
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(DownloadConfig, media_dir, max_per_host,
                                                connect_timeout_s, low_speed_time_s,
                                                low_speed_bytes_per_s, total_timeout_s, retries,
                                                retry_backoff_s, command, command_hosts, format,
                                                max_height, user_agent)

// Throws Error("bad_config") naming section.key for a value out of range.
void CheckConfig(const DownloadConfig& c, const std::string& section);

// What one clip's download did, as `report` reads it back from the stage's
// measurements summary.
struct DownloadSummary {
  std::string source;  // "local", "reused", "http" or "command"
  std::int64_t bytes = 0;       // transferred by this run
  std::int64_t size_bytes = 0;  // of the file
  double seconds = 0;           // transfer time, retries and waits included
};
Json ToJson(const DownloadSummary& s);
// Reads the "summary" member the stage wrote; throws Error("bad_measurements").
DownloadSummary ReadDownloadSummary(const Json& summary);

// The stage-independent part: makes sure `url` is a complete local file in
// `media_dir` and says how (used by the stage and the benchmark). `log_dir`
// receives the command's log. Throws as the file comment says.
struct DownloadOutcome {
  std::filesystem::path path;
  std::string sha256;
  DownloadSummary summary;
  std::int64_t resumed_from = 0;
  int tries = 0;
};
// Whether a clip's video is a URL (anything with "://") rather than a file.
bool IsUrl(const std::string& s);

DownloadOutcome DownloadVideo(const std::string& url, const std::filesystem::path& media_dir,
                              const std::filesystem::path& log_dir, const DownloadConfig& config);

}  // namespace doasido::ingest
