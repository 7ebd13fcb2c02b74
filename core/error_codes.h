// Error codes that more than one module reads, and for each whether a retry
// can help. The worker fails a run at its first attempt when its error is
// permanent (IsPermanentError), so a deterministic failure never spends the
// attempts meant for a busy disk or a flaky network.
#pragma once

#include <string_view>

#include "core/bounded_text.h"  // kMeasurementsTooLarge

namespace doasido {

// A video file FFmpeg cannot open, or that holds fewer frames than it
// declares (video/frame_count.h), or that names a URL never downloaded.
inline constexpr const char* kVideoUnreadable = "video_unreadable";
inline constexpr const char* kVideoTruncated = "video_truncated";
inline constexpr const char* kVideoNotDownloaded = "video_not_downloaded";
// A file that is not a regular file (FIFO, device, folder, socket): it may
// never end, so it is refused without being opened.
inline constexpr const char* kNotARegularFile = "not_a_regular_file";
// A video no stage can judge: too small to show a hand, an absurd size or
// rate, no frames, audio only, a still image under a video's name.
inline constexpr const char* kUnsupportedVideo = "unsupported_video";
// A stage run went past its wall-clock limit (stages/stage_timeouts.h). A
// stage whose same input gives the same outcome would run as long again, so
// its timeout is permanent; a stage that waits on the outside world (the
// network) may be quicker next time: kStageTimeoutTransient, retried. The
// stage's registry entry says which it is (StageEntry::deterministic).
inline constexpr const char* kStageTimeout = "stage_timeout";
inline constexpr const char* kStageTimeoutTransient = "stage_timeout_transient";

// Failures that are the input's, not the moment's (each a retry would
// meet again): a site that answered 404/410 or refused the request (another
// 4xx), a URL no client can fetch, no download command for the site, a video
// the site says is gone or blocked in this country, camera intrinsics that
// are not numbers, a clip with no bundle or one that does not read, a track
// that does not read, a model server that says a retry cannot help.
inline constexpr const char* kHttpNotFound = "http_not_found";
inline constexpr const char* kHttpRefused = "http_refused";
inline constexpr const char* kBadUrl = "bad_url";
inline constexpr const char* kNoDownloadCommand = "no_download_command";
inline constexpr const char* kVideoUnavailable = "video_unavailable";
inline constexpr const char* kGeoBlocked = "geo_blocked";
inline constexpr const char* kBadIntrinsics = "bad_intrinsics";
inline constexpr const char* kNoBundle = "no_bundle";
inline constexpr const char* kBadBundle = "bad_bundle";
// A clip's object prompt (ingest/object_prompt.h) that cannot be used.
inline constexpr const char* kBadObjectBox = "bad_object_box";
inline constexpr const char* kBadTrack = "bad_track";
inline constexpr const char* kBundleServerRefused = "bundle_server_refused";

// A database that cannot be written (a read-only mount or file): it is
// opened read-only for the commands that only look, and every write is
// refused with this code, naming the file (db/database.h).
inline constexpr const char* kReadOnly = "read_only";

// The one table of what a retry cannot fix: the same input gives the same
// error, so the worker fails such a run at its first attempt. The code
// alone decides; codes not listed are transient (a retry may succeed: a
// busy disk, a flaky network, a server that died).
inline bool IsPermanentError(std::string_view code) {
  for (const std::string_view permanent :
       {std::string_view(kNotARegularFile), std::string_view(kUnsupportedVideo),
        std::string_view(kVideoUnreadable), std::string_view(kVideoTruncated),
        std::string_view(kVideoNotDownloaded), std::string_view("bad_config"),
        std::string_view("bad_embodiment"),  // a hand description that does not load
        std::string_view("bad_span"), std::string_view(kHttpNotFound),
        std::string_view(kHttpRefused), std::string_view(kBadUrl),
        std::string_view(kNoDownloadCommand), std::string_view(kVideoUnavailable),
        std::string_view(kGeoBlocked), std::string_view(kBadIntrinsics),
        std::string_view(kNoBundle), std::string_view(kBadBundle), std::string_view(kBadTrack),
        std::string_view(kBadObjectBox),
        std::string_view(kBundleServerRefused), std::string_view(kMeasurementsTooLarge),
        std::string_view(kStageTimeout), std::string_view(kReadOnly)}) {
    if (code == permanent) return true;
  }
  return false;
}

}  // namespace doasido
