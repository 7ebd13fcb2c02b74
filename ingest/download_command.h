// Downloading a video through an external command (yt-dlp or a wrapper of
// the user's) built from a template, with its failures named.
//
// Template placeholders, each replaced by a single-quoted shell word:
//   {url}         the video's URL as listed
//   {id}          the site's video id (YouTube: the v= parameter or the
//                 youtu.be path), else a hash of the URL
//   {output}      the file the command must create (…/media/<host>/<id>.mp4)
//   {output_dir}  its folder
//   {format}      the configured format selector, with {max_height} inside
//                 it already replaced
//   {max_height}  the configured maximum frame height
// The command runs under /bin/sh; stdout and stderr go to a log file.
//
// Example (yt-dlp; mp4 at most 720 lines high, merged into one file):
//   yt-dlp --no-playlist --no-progress -f {format} --merge-output-format mp4
//          -o {output} {url}
//   with format = "bv*[height<={max_height}][ext=mp4]+ba[ext=m4a]/b[height<={max_height}]"
//
// How the outcome is read:
//   exit 0 and {output} exists               success
//   exit 11, or yt-dlp saying "... available in your country", "geo
//     restrict", "blocked it in your country"   geo_blocked (permanent)
//   exit 10, or "Video unavailable", "Private video", "has been removed",
//     "account ... terminated"               video_unavailable (permanent)
//   exit 12, or "HTTP Error 429", "Too Many Requests", "rate-limit"
//                                            rate_limited (retried with back-off)
//   anything else                            download_failed, with the last
//                                            lines of the command's output
// A wrapper script can therefore name a failure by its exit status alone.
#pragma once

#include <filesystem>
#include <string>

namespace doasido::ingest {

inline constexpr int kExitVideoUnavailable = 10;
inline constexpr int kExitGeoBlocked = 11;
inline constexpr int kExitRateLimited = 12;

struct DownloadCommand {
  std::string command_template;
  std::string format;
  int max_height = 720;
};

// The site's id for `url`: YouTube's 11-character id when the URL is a
// YouTube watch, youtu.be, shorts or embed URL, else 16 hex digits of a
// hash of the URL.
std::string VideoIdOf(const std::string& url);

// Runs the command for `url`, writing to `output` and logging to `log`.
// Throws the errors listed in the file comment (video_unavailable,
// geo_blocked and no_download_command are permanent: core/error_codes.h)
// naming `url`.
void RunDownloadCommand(const DownloadCommand& command, const std::string& url,
                        const std::filesystem::path& output, const std::filesystem::path& log);

// The last `n` non-empty lines of `text`, joined by " | ".
std::string LastLines(const std::string& text, int n);

}  // namespace doasido::ingest
