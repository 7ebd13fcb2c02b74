// Fetching one http(s) URL into a file with libcurl, resumably: the bytes
// go to `<dest>.part`, a later call continues it with a range request, and
// only a complete transfer is renamed to `dest`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace doasido::ingest {

struct HttpFetchOptions {
  double connect_timeout_s = 15;
  // Abort (Error "download_timeout") when fewer than low_speed_bytes_per_s
  // arrive per second for low_speed_time_s seconds (rounded up to whole
  // seconds, libcurl's unit), or when the whole transfer takes longer than
  // total_timeout_s (0: no limit).
  double low_speed_time_s = 30;
  double low_speed_bytes_per_s = 1024;
  double total_timeout_s = 0;
  std::string user_agent = "doasido";
};

struct HttpFetchResult {
  std::int64_t size_bytes = 0;        // of the finished file
  std::int64_t bytes_transferred = 0; // by this call (less than size when resumed)
  std::int64_t resumed_from = 0;      // bytes of .part kept from an earlier call
  int http_status = 0;
  double seconds = 0;
  // SHA-256 of the finished file, computed as the bytes arrived (a resumed
  // .part's prefix is read back once).
  std::string sha256;
};

// Fetches `url` into `dest` (through `<dest>.part`; parent folders are
// created). Follows redirects. Throws:
//  - "http_not_found" (404, 410), "http_refused" (other 4xx but 408 and
//    429) and "bad_url": a retry gets the same answer (permanent codes,
//    core/error_codes.h);
//  - Error "download_timeout" (connect or low-speed timeout),
//    "rate_limited" (429), "http_error" (5xx, 408), "connection_failed",
//    "transfer_interrupted" (the connection closed early: .part is kept for
//    the next call to resume), "download_incomplete" (fewer bytes than the
//    server announced).
// Every error names `url` in its site's file field.
HttpFetchResult FetchUrl(const std::string& url, const std::filesystem::path& dest,
                         const HttpFetchOptions& options);

// The host of a URL ("example.org" for "https://user@Example.org:8080/x"),
// lower-cased; empty when there is none.
std::string UrlHost(const std::string& url);

}  // namespace doasido::ingest
