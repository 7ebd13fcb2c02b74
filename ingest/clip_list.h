// Clip-list readers. Each reader turns one list file (or annotation folder)
// into rows ready for the database plus a list of the rows it refused, each
// named by file, line and field, so one bad row never stops a batch.
//
// Formats (REFERENCE.md §1):
//  - CSV / TSV / JSONL with a header (JSONL: one object per line). Columns:
//      video | path | video_path | url | file   the video (required); a
//                                 relative path is relative to the list file
//      id | clip_id | narration_id             optional external id
//      start_frame, end_frame | stop_frame     inclusive frame numbers
//      start_time | start_timestamp | start_s, end_time | stop_timestamp | end_s
//                                 seconds, or HH:MM:SS(.fff), or MM:SS(.fff)
//      start, end                 a frame number if a plain integer, else a time
//    Every other column is kept as clip metadata.
//  - EPIC-KITCHENS-100 annotation CSV (header starts with narration_id) with
//    its EPIC_100_video_info.csv (per-video fps): frames and timestamps both
//    kept; videos are <video_root>/<participant_id>/videos/<video_id>.MP4.
//    EPIC frame numbers count at 60 per second for every video, whatever its
//    real rate: metadata "frame_numbers_fps" = 60 says so.
//  - 100DOH VOC annotation folders: Annotations/*.xml, one per frame named
//    <genre>_v_<video id>_frame<6 digits>; frames of one video id become one
//    clip spanning them, boxes and contact states become detections.
//  - Plain text lists of 100DOH-family frame names (one per line): frames are
//    grouped per video into clips like VOC folders, without boxes.
//  - VOC folders and frame-name lists whose videos are absent name them by
//    id through ListOptions::video_url_template ("...watch?v={id}"): a
//    video missing from the video folder becomes that URL, for the
//    download stage to fetch.
//  - .json files holding one JSON document: an array of clip objects (as
//    JSONL lines), or an object mapping video ids to objects of metadata
//    (WiLoR's "whim" layout: {"<youtubeId>": {"resolution": ..., "fps": ...}})
//    read as one whole-video clip per id, video = the URL template applied
//    to the id (default https://www.youtube.com/watch?v={id}), the id as
//    external id and the object's fields as metadata.
//  An empty file (or only white space) is refused whole as kEmptyList, the
//  same for every format. A FIFO or other non-regular file is refused as
//  kNotARegularFile without being read. A file that is not a clip list at all (a JSON scalar or an object of
//  scalars, a JSON/JSONL file none of whose lines is an object, a text file
//  none of whose lines is a frame name) is refused whole with an Error
//  saying what was expected, never read as one bad row.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/records.h"

namespace doasido::ingest {

// An empty (or all white space) list file of any format: refused whole.
inline constexpr const char* kEmptyList = "empty_list";

struct ListRow {
  long line = 0;             // 1-based line (or file index for VOC) in the list
  std::string video;         // absolute path, or URL
  ClipRecord clip;           // video_id unset; source_list/source_line set
  std::vector<Detection> detections;
};

struct RowError {
  std::string file;
  long line = 0;
  std::string field;
  std::string reason;
  std::string Format() const;  // "file:line: field: reason"
};

struct ListReadResult {
  std::string format;  // "csv", "tsv", "jsonl", "json", "idmap", "epic", "voc", "framenames"
  std::vector<ListRow> rows;
  std::vector<RowError> errors;
};

struct ListOptions {
  // Refuse rows whose local video file does not exist (URLs are not checked).
  bool check_files = true;
  // EPIC: folder holding <participant>/videos/<video>.MP4, and the video
  // info CSV (default: EPIC_100_video_info.csv beside the list).
  std::filesystem::path epic_video_root;
  std::filesystem::path epic_video_info;
  // VOC and frame-name lists: folder with <video id>.mp4 (default: videos/
  // beside the Annotations folder) and a factor from annotated frame numbers
  // to video frame numbers (e.g. the sampling stride).
  std::filesystem::path voc_video_dir;
  double voc_frame_scale = 1.0;
  // VOC, frame names and JSON id maps: the URL of a video id, "{id}"
  // replaced (e.g. "https://www.youtube.com/watch?v={id}"). VOC and frame
  // names use it for ids without a file in the video folder.
  std::string video_url_template;
};

// The URL template JSON id maps use when ListOptions gives none.
inline constexpr const char* kYoutubeUrlTemplate = "https://www.youtube.com/watch?v={id}";

// Reads any supported list, choosing the reader from the path (a folder is
// VOC; .jsonl/.json lines; .tsv; .txt frame names; .csv, EPIC by header).
// Throws Error only when the file as a whole is unreadable (missing, no
// header, no video column); row problems go to `errors`.
ListReadResult ReadClipList(const std::filesystem::path& path, const ListOptions& options = {});

// Parses a time: plain seconds ("12.5"), "MM:SS(.fff)" or "HH:MM:SS(.fff)".
// Returns nullopt for anything else, negative values, NaN or infinity.
std::optional<double> ParseTimestamp(const std::string& text);

// A 100DOH-family frame name split into its parts.
struct FrameName {
  std::string genre;  // "boardgame", or the dataset for egocentric names ("EK")
  std::string split;  // egocentric names only ("test")
  std::string video;  // YouTube id or egocentric video id ("P24-09")
  std::int64_t frame = 0;
};
// Accepts "<genre>_v_<id>_frame<digits>" and "<dataset>_<split>_<video>_<digits>".
std::optional<FrameName> ParseFrameName(const std::string& name);

}  // namespace doasido::ingest
