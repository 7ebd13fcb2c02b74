// Plain rows of the doasido database, as the stages and commands see them.
// Paths are absolute here; the database stores them relative to its folder
// so that a database folder can be moved as a whole. They live in core, not
// db/, because the domain folders fill them without a database: the probe
// (video/probe.h) a VideoInfo, the list readers (ingest/clip_list.h) a
// ClipRecord, the detectors (filters/) Detections and the verdict rules a
// Verdict; db/ stores and loads them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"

namespace doasido {

using ClipId = std::int64_t;
using VideoId = std::int64_t;

// What the probe stage learns about a video file.
struct VideoInfo {
  int width = 0;   // as displayed (after rotation_deg), like decoded frames
  int height = 0;
  double fps = 0;
  std::int64_t frame_count = 0;  // frames actually decoded (or declared, see probe)
  double duration_s = 0;
  bool variable_frame_rate = false;
  int rotation_deg = 0;  // display rotation from container metadata (video/display_rotation.h)
  std::string codec;     // FourCC, e.g. "avc1"
};

struct VideoRecord {
  VideoId id = 0;
  std::string path;  // absolute path, or URL as given
  std::optional<VideoInfo> info;  // set once probed
};

// A clip is a span of one video. Frame numbers and timestamps are as in the
// source list; either pair may be absent (then the clip is the whole video).
struct ClipRecord {
  ClipId id = 0;
  VideoId video_id = 0;
  std::string external_id;  // id from the list (narration_id, frame name, ...)
  std::optional<std::int64_t> start_frame, end_frame;  // inclusive
  std::optional<double> start_s, end_s;
  std::string source_list;  // file the clip was ingested from
  long source_line = 0;
  Json metadata = Json::object();  // other columns of the list row
};

// One hand or object box on one frame (100DOH / detector format, REFERENCE §1).
struct Detection {
  std::int64_t frame = 0;
  std::string kind;  // "hand" or "object"
  double x1 = 0, y1 = 0, x2 = 0, y2 = 0;  // pixels, 0-based, x2/y2 exclusive
  double score = 1.0;
  int contact_state = -1;  // hands: 0 N, 1 S, 2 O, 3 P, 4 F; -1 unknown
  int hand_side = -1;      // hands: 0 left, 1 right; -1 unknown
  double dx = 0, dy = 0, magnitude = 0;  // hand -> object offset (unit vector, px)
  std::string source;  // "100doh_voc", "synth", "detector:<name>", ...
};

// kNotMeasured: the stage's measurement did not run for the clip because an
// earlier verdict in the order the evidence is taken (a cheap one, taken
// before the costly measurement) removed it; the run's reason names that
// verdict's stage. It moves the clip on like pass but judges nothing: it is
// never counted as passed, flagged or rejected (filters/README.md, "Not
// measured").
enum class Verdict { kPass, kReject, kFlag, kNotMeasured };
const char* ToString(Verdict v);
Verdict VerdictFromString(const std::string& s);  // throws Error

}  // namespace doasido
