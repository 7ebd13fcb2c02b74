#include "ingest/http_fetch.h"

#include <curl/curl.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <mutex>

#include "core/error.h"
#include "core/error_codes.h"
#include "ingest/file_sha256.h"

namespace doasido::ingest {
namespace {

namespace fs = std::filesystem;

void GlobalInit() {
  static std::once_flag once;
  std::call_once(once, [] { curl_global_init(CURL_GLOBAL_DEFAULT); });
}

// What the write callback needs: the .part file, whether a range was asked
// for, and the status of the response the body belongs to.
struct Transfer {
  CURL* curl = nullptr;
  fs::path part;
  std::int64_t resume_from = 0;
  std::FILE* file = nullptr;
  bool decided = false;  // status seen and file opened
  long status = 0;
  std::int64_t written = 0;
  bool write_failed = false;
  std::unique_ptr<Sha256> sha;  // of the .part from its first byte
};

size_t OnBody(char* data, size_t size, size_t count, void* user) {
  auto* t = static_cast<Transfer*>(user);
  const size_t n = size * count;
  if (!t->decided) {
    t->decided = true;
    curl_easy_getinfo(t->curl, CURLINFO_RESPONSE_CODE, &t->status);
    if (t->status == 200 || t->status == 206) {
      // 200 to a range request: the server sends the whole file again.
      const bool append = t->status == 206 && t->resume_from > 0;
      if (!append) t->resume_from = 0;
      t->file = std::fopen(t->part.c_str(), append ? "ab" : "wb");
      try {
        // No exception may cross libcurl's C frames.
        t->sha = std::make_unique<Sha256>();
        if (append) t->sha->UpdateFromFile(t->part);
      } catch (const std::exception&) {
        t->sha.reset();
      }
      if (t->file == nullptr || !t->sha) {
        t->write_failed = true;
        return 0;
      }
    }
  }
  if (t->file == nullptr) return n;  // an error page: read and drop it
  if (std::fwrite(data, 1, n, t->file) != n) {
    t->write_failed = true;
    return 0;
  }
  t->sha->Update(data, n);
  t->written += static_cast<std::int64_t>(n);
  return n;
}

[[noreturn]] void ThrowForStatus(long status, const std::string& url) {
  const ErrorSite site{.file = url};
  const std::string text = "HTTP " + std::to_string(status);
  if (status == 404 || status == 410) throw Error(kHttpNotFound, text, site);
  if (status == 429) throw Error("rate_limited", text + " (too many requests)", site);
  if (status >= 400 && status < 500 && status != 408) {
    throw Error(kHttpRefused, text, site);
  }
  throw Error("http_error", text, site);
}

[[noreturn]] void ThrowForCurl(CURLcode code, const char* detail, const std::string& url,
                               bool kept_part) {
  const ErrorSite site{.file = url};
  std::string text = std::string(curl_easy_strerror(code)) + (detail[0] ? ": " : "") + detail;
  switch (code) {
    case CURLE_OPERATION_TIMEDOUT:
      throw Error("download_timeout", text, site);
    case CURLE_COULDNT_RESOLVE_HOST:
    case CURLE_COULDNT_RESOLVE_PROXY:
    case CURLE_COULDNT_CONNECT:
      throw Error("connection_failed", text, site);
    case CURLE_UNSUPPORTED_PROTOCOL:
    case CURLE_URL_MALFORMAT:
      throw Error(kBadUrl, text, site);
    default:
      if (kept_part) text += " (the partial file is kept and resumed next time)";
      throw Error("transfer_interrupted", text, site);
  }
}

}  // namespace

std::string UrlHost(const std::string& url) {
  const auto scheme = url.find("://");
  if (scheme == std::string::npos) return "";
  auto begin = scheme + 3;
  const auto end = std::min(url.find_first_of("/?#", begin), url.size());
  const auto at = url.rfind('@', end);
  if (at != std::string::npos && at >= begin) begin = at + 1;
  std::string host = url.substr(begin, end - begin);
  if (!host.empty() && host[0] == '[') {
    host = host.substr(0, host.find(']') + 1);  // IPv6 literal
  } else {
    host = host.substr(0, host.find(':'));
  }
  std::transform(host.begin(), host.end(), host.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return host;
}

HttpFetchResult FetchUrl(const std::string& url, const fs::path& dest,
                         const HttpFetchOptions& options) {
  GlobalInit();
  const auto start = std::chrono::steady_clock::now();
  fs::create_directories(dest.parent_path());
  Transfer t;
  t.part = dest.string() + ".part";
  std::error_code ec;
  if (fs::exists(t.part, ec)) t.resume_from = static_cast<std::int64_t>(fs::file_size(t.part, ec));
  if (ec) t.resume_from = 0;

  std::unique_ptr<CURL, void (*)(CURL*)> curl(curl_easy_init(), &curl_easy_cleanup);
  if (!curl) throw Error("download_failed", "libcurl cannot start a transfer", {.file = url});
  t.curl = curl.get();
  char detail[CURL_ERROR_SIZE] = {0};
  CURL* c = curl.get();
  curl_easy_setopt(c, CURLOPT_URL, url.c_str());
  curl_easy_setopt(c, CURLOPT_ERRORBUFFER, detail);
  curl_easy_setopt(c, CURLOPT_NOSIGNAL, 1L);
  curl_easy_setopt(c, CURLOPT_FOLLOWLOCATION, 1L);
  curl_easy_setopt(c, CURLOPT_MAXREDIRS, 10L);
  curl_easy_setopt(c, CURLOPT_PROTOCOLS_STR, "http,https");
  curl_easy_setopt(c, CURLOPT_REDIR_PROTOCOLS_STR, "http,https");
  curl_easy_setopt(c, CURLOPT_USERAGENT, options.user_agent.c_str());
  curl_easy_setopt(c, CURLOPT_CONNECTTIMEOUT_MS,
                   static_cast<long>(std::lround(options.connect_timeout_s * 1000)));
  curl_easy_setopt(c, CURLOPT_LOW_SPEED_LIMIT,
                   static_cast<long>(std::lround(options.low_speed_bytes_per_s)));
  curl_easy_setopt(c, CURLOPT_LOW_SPEED_TIME,
                   std::max(1L, static_cast<long>(std::ceil(options.low_speed_time_s))));
  if (options.total_timeout_s > 0) {
    curl_easy_setopt(c, CURLOPT_TIMEOUT_MS,
                     static_cast<long>(std::lround(options.total_timeout_s * 1000)));
  }
  if (t.resume_from > 0) {
    // A plain Range header: libcurl's own resume refuses a 200 answer, which
    // OnBody handles by starting over.
    curl_easy_setopt(c, CURLOPT_RANGE, (std::to_string(t.resume_from) + "-").c_str());
  }
  curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, &OnBody);
  curl_easy_setopt(c, CURLOPT_WRITEDATA, &t);
  const CURLcode code = curl_easy_perform(c);
  if (t.file != nullptr) std::fclose(t.file);
  long status = t.status;
  if (status == 0) curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, &status);
  if (t.write_failed) {
    throw Error("io", "cannot write the partial download", {.file = t.part.string()});
  }
  if (status == 416) {
    // The range starts at or past the end: the .part is not a prefix we can
    // trust; start over next time.
    fs::remove(t.part, ec);
    throw Error("transfer_interrupted", "HTTP 416 for a resumed range; restarting from 0",
                {.file = url});
  }
  if (status >= 400) ThrowForStatus(status, url);
  if (code != CURLE_OK) ThrowForCurl(code, detail, url, fs::exists(t.part, ec));
  if (status != 200 && status != 206) ThrowForStatus(status, url);

  if (!fs::exists(t.part, ec)) std::ofstream(t.part).close();  // an empty body
  curl_off_t announced = -1;
  curl_easy_getinfo(c, CURLINFO_CONTENT_LENGTH_DOWNLOAD_T, &announced);
  const auto size = static_cast<std::int64_t>(fs::file_size(t.part, ec));
  if (announced >= 0 && size != t.resume_from + static_cast<std::int64_t>(announced)) {
    throw Error("download_incomplete",
                "have " + std::to_string(size) + " bytes, expected " +
                    std::to_string(t.resume_from + announced),
                {.file = url});
  }
  fs::rename(t.part, dest);
  HttpFetchResult result;
  result.size_bytes = size;
  result.bytes_transferred = t.written;
  result.resumed_from = t.resume_from;
  result.http_status = static_cast<int>(status);
  result.sha256 = t.sha ? t.sha->HexDigest() : FileSha256(dest);
  result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace doasido::ingest
