#include "ingest/download.h"

#include <algorithm>
#include <cctype>
#include <optional>
#include <chrono>
#include <cmath>
#include <fstream>
#include <thread>

#include "core/clock.h"
#include "core/config_check.h"
#include "core/error.h"
#include "core/error_codes.h"
#include "ingest/download_command.h"
#include "ingest/file_sha256.h"
#include "ingest/host_slots.h"
#include "ingest/http_fetch.h"

namespace doasido::ingest {
namespace {

namespace fs = std::filesystem;

std::string SafeFileName(const std::string& s, size_t max_length) {
  std::string out;
  for (const char c : s) {
    if (out.size() >= max_length) break;
    out += std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_' ? c
                                                                                           : '_';
  }
  return out;
}

// The last path segment of a URL, without query or fragment.
std::string UrlBaseName(const std::string& url) {
  const auto scheme = url.find("://");
  const auto path_begin = url.find('/', scheme == std::string::npos ? 0 : scheme + 3);
  if (path_begin == std::string::npos) return "";
  const auto path_end = std::min(url.find_first_of("?#", path_begin), url.size());
  const std::string path = url.substr(path_begin, path_end - path_begin);
  return path.substr(path.rfind('/') + 1);
}

bool UsesCommand(const std::string& host, const DownloadConfig& config) {
  return std::find(config.command_hosts.begin(), config.command_hosts.end(), host) !=
         config.command_hosts.end();
}

fs::path DestinationOf(const std::string& url, const fs::path& media_dir,
                       const DownloadConfig& config) {
  const std::string host = UrlHost(url);
  const fs::path dir = media_dir / SafeFileName(host.empty() ? "_" : host, 100);
  if (UsesCommand(host, config)) {
    // Every YouTube URL form of one video is one file.
    const std::string id = VideoIdOf(url);
    const bool youtube = id.size() == 11;
    return (youtube ? media_dir / "youtube" : dir) / (SafeFileName(id, 64) + ".mp4");
  }
  const std::string base = SafeFileName(UrlBaseName(url), 80);
  return dir / (ParamHash(url) + (base.empty() ? "" : "-" + base));
}

fs::path SidecarOf(const fs::path& file) { return file.string() + ".json"; }

// The sidecar of a finished download, when it and its file agree.
std::optional<Json> FinishedDownload(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec) || !fs::exists(SidecarOf(file), ec)) return std::nullopt;
  try {
    std::ifstream in(SidecarOf(file));
    Json j = Json::parse(in);
    const auto size = static_cast<std::int64_t>(fs::file_size(file, ec));
    if (!ec && j.value("size_bytes", std::int64_t{-1}) == size) return j;
  } catch (const std::exception&) {
  }
  return std::nullopt;  // torn sidecar or a replaced file: download again
}

void WriteSidecar(const fs::path& file, const Json& sidecar) {
  const fs::path tmp = SidecarOf(file).string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << sidecar.dump(2) << "\n";
    if (!out) throw Error("io", "cannot write download sidecar", {.file = tmp.string()});
  }
  fs::rename(tmp, SidecarOf(file));
}

// Runs `fetch` up to 1 + retries times, waiting with doubling back-off
// after transient failures. A permanent error (IsPermanentError) ends it at
// once.
template <typename Fn>
void WithRetries(const DownloadConfig& config, int& tries, Fn fetch) {
  for (int attempt = 0;; ++attempt) {
    ++tries;
    try {
      fetch();
      return;
    } catch (const Error& e) {
      if (IsPermanentError(e.code()) || attempt >= config.retries) throw;
      const double wait = config.retry_backoff_s * std::pow(2.0, attempt);
      std::this_thread::sleep_for(std::chrono::duration<double>(wait));
    }
  }
}


}  // namespace

bool IsUrl(const std::string& s) { return s.find("://") != std::string::npos; }

void CheckConfig(const DownloadConfig& c, const std::string& section) {
  RequireInRange(section, "max_per_host", c.max_per_host, 1, 1024);
  RequireInRange(section, "connect_timeout_s", c.connect_timeout_s, 0.001, 3600);
  RequireInRange(section, "low_speed_time_s", c.low_speed_time_s, 1, 86400);
  RequireInRange(section, "low_speed_bytes_per_s", c.low_speed_bytes_per_s, 1, 1e12);
  RequireInRange(section, "total_timeout_s", c.total_timeout_s, 0, 1e7);
  RequireInRange(section, "retries", c.retries, 0, 100);
  RequireInRange(section, "retry_backoff_s", c.retry_backoff_s, 0, 3600);
  RequireInRange(section, "max_height", c.max_height, 1, 100000);
}

Json ToJson(const DownloadSummary& s) {
  return {{"source", s.source},
          {"bytes", s.bytes},
          {"size_bytes", s.size_bytes},
          {"seconds", s.seconds}};
}

DownloadSummary ReadDownloadSummary(const Json& summary) {
  if (!summary.is_object() || !summary.contains("source")) {
    throw Error("bad_measurements", "download summary without a source",
                {.field = std::string(kDownloadStageName) + ".summary"});
  }
  DownloadSummary s;
  s.source = summary.at("source").get<std::string>();
  s.bytes = summary.value("bytes", std::int64_t{0});
  s.size_bytes = summary.value("size_bytes", std::int64_t{0});
  s.seconds = summary.value("seconds", 0.0);
  return s;
}

DownloadOutcome DownloadVideo(const std::string& url, const fs::path& media_dir,
                              const fs::path& log_dir, const DownloadConfig& config) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path dest = DestinationOf(url, media_dir, config);
  fs::create_directories(dest.parent_path());
  // One worker per file: the others wait here, then find it finished.
  FileLock file_lock(media_dir / ".locks" /
                     (dest.parent_path().filename().string() + "_" + dest.filename().string() +
                      ".lock"));
  DownloadOutcome out;
  out.path = dest;
  if (auto done = FinishedDownload(dest)) {
    out.sha256 = done->value("sha256", "");
    out.summary = {.source = "reused", .size_bytes = done->value("size_bytes", std::int64_t{0})};
    return out;
  }
  const std::string host = UrlHost(url);
  if (UsesCommand(host, config)) {
    const DownloadCommand command{config.command, config.format, config.max_height};
    WithRetries(config, out.tries, [&] {
      HostSlot slot(media_dir / ".locks", host, config.max_per_host);
      RunDownloadCommand(command, url, dest, log_dir / "download.log");
    });
    out.summary.source = "command";
    out.summary.bytes = static_cast<std::int64_t>(fs::file_size(dest));
    out.sha256 = FileSha256(dest);
  } else {
    const HttpFetchOptions http{config.connect_timeout_s, config.low_speed_time_s,
                                config.low_speed_bytes_per_s, config.total_timeout_s,
                                config.user_agent};
    bool first = true;
    WithRetries(config, out.tries, [&] {
      HostSlot slot(media_dir / ".locks", host, config.max_per_host);
      const HttpFetchResult r = FetchUrl(url, dest, http);
      out.sha256 = r.sha256;
      out.summary.bytes += r.bytes_transferred;
      if (first) out.resumed_from = r.resumed_from;
      first = false;
    });
    out.summary.source = "http";
  }
  out.summary.size_bytes = static_cast<std::int64_t>(fs::file_size(dest));
  WriteSidecar(dest, {{"url", url}, {"size_bytes", out.summary.size_bytes},
                      {"sha256", out.sha256}, {"downloaded_at", Now()}});
  out.summary.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace doasido::ingest
