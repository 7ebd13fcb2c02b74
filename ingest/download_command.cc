#include "ingest/download_command.h"

#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "core/config.h"
#include "core/file_text.h"
#include "core/error.h"
#include "core/error_codes.h"
#include "core/shell_words.h"
#include "ingest/http_fetch.h"

namespace doasido::ingest {
namespace {

namespace fs = std::filesystem;

bool IsYoutubeIdChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_';
}

// The id that follows `marker` in `url` when it is 11 id characters long.
std::string IdAfter(const std::string& url, const std::string& marker) {
  const auto at = url.find(marker);
  if (at == std::string::npos) return "";
  const auto begin = at + marker.size();
  auto end = begin;
  while (end < url.size() && IsYoutubeIdChar(url[end])) ++end;
  return end - begin == 11 ? url.substr(begin, 11) : "";
}

bool Says(const std::string& text, const std::vector<std::string>& needles) {
  std::string lower = text;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return std::any_of(needles.begin(), needles.end(), [&lower](const std::string& n) {
    return lower.find(n) != std::string::npos;
  });
}

}  // namespace

std::string VideoIdOf(const std::string& url) {
  const std::string host = UrlHost(url);
  if (host.find("youtube.com") != std::string::npos || host == "youtu.be" ||
      host.find("youtube-nocookie.com") != std::string::npos) {
    for (const char* marker : {"?v=", "&v=", "youtu.be/", "/shorts/", "/embed/", "/live/"}) {
      const std::string id = IdAfter(url, marker);
      if (!id.empty()) return id;
    }
  }
  return ParamHash(url);
}

std::string LastLines(const std::string& text, int n) {
  std::vector<std::string> lines;
  std::stringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") != std::string::npos) lines.push_back(line);
  }
  std::string out;
  for (size_t i = lines.size() > static_cast<size_t>(n) ? lines.size() - n : 0; i < lines.size();
       ++i) {
    out += (out.empty() ? "" : " | ") + lines[i];
  }
  return out;
}

void RunDownloadCommand(const DownloadCommand& command, const std::string& url,
                        const fs::path& output, const fs::path& log) {
  const ErrorSite site{.file = url, .field = "command"};
  if (command.command_template.empty()) {
    throw Error(kNoDownloadCommand,
                         "no download command is configured for this site (set download.command, "
                         "e.g. a yt-dlp template; see README)",
                         site);
  }
  std::string format = command.format;
  ReplaceAll(format, "{max_height}", std::to_string(command.max_height));
  std::string text = command.command_template;
  ReplaceAll(text, "{url}", ShellQuote(url));
  ReplaceAll(text, "{id}", ShellQuote(VideoIdOf(url)));
  ReplaceAll(text, "{output}", ShellQuote(output.string()));
  ReplaceAll(text, "{output_dir}", ShellQuote(output.parent_path().string()));
  ReplaceAll(text, "{format}", ShellQuote(format));
  ReplaceAll(text, "{max_height}", ShellQuote(std::to_string(command.max_height)));
  fs::create_directories(output.parent_path());
  fs::create_directories(log.parent_path());
  std::error_code ec;
  fs::remove(output, ec);  // only a file this run wrote counts
  const std::string shell = "( " + text + " ) >" + ShellQuote(log.string()) + " 2>&1 </dev/null";
  const int status = std::system(shell.c_str());
  const std::string said = TryReadFile(log).value_or("");
  const int exit_code = status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (exit_code == 0 && fs::exists(output)) return;
  const std::string tail = LastLines(said, 5);
  const std::string how = "command exited " + std::to_string(exit_code) + ": " + tail;
  // Geo messages first: "This video is not available in your country" also
  // reads as unavailable.
  if (exit_code == kExitGeoBlocked ||
      Says(said, {"available in your country", "geo restrict", "geo-restrict",
                  "blocked it in your country"})) {
    throw Error(kGeoBlocked, how, site);
  }
  if (exit_code == kExitVideoUnavailable ||
      Says(said, {"video unavailable", "private video", "has been removed",
                  "account associated with this video has been terminated",
                  "this video is not available", "video is unavailable"})) {
    throw Error(kVideoUnavailable, how, site);
  }
  if (exit_code == kExitRateLimited ||
      Says(said, {"http error 429", "too many requests", "rate-limit", "rate limit"})) {
    throw Error("rate_limited", how, site);
  }
  if (exit_code == 0) {
    throw Error("download_failed", "command exited 0 but did not create " + output.string() +
                                       (tail.empty() ? "" : ": " + tail),
                site);
  }
  throw Error("download_failed", how, site);
}

}  // namespace doasido::ingest
