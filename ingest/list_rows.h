// What a row of a clip list means, whatever its format (ingest/clip_list.cc
// reads CSV/TSV, JSON Lines, JSON documents, EPIC tables, 100DOH VOC
// folders and frame-name lists into named cells): the roles of columns,
// frame and time spans, the video path or URL, the checks every row gets
// (video present and found, span ordered, no duplicate), and the small
// text helpers the readers share. Internal to ingest.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/config.h"
#include "ingest/clip_list.h"
#include "ingest/object_prompt.h"

namespace doasido::ingest::rows {

namespace fs = std::filesystem;

inline constexpr std::int64_t kMaxFrame = 1'000'000'000;  // ~1 year at 30 fps
inline constexpr double kMaxSeconds = 1e7;                 // ~115 days

// True when `s` is valid UTF-8.
bool IsUtf8(const std::string& s);
// `s` without leading and trailing spaces, tabs, CRs and LFs.
std::string Trim(const std::string& s);
std::string Lower(std::string s);
bool IsUrl(const std::string& s);
// `url_template` with every {id} replaced by `id`.
std::string VideoUrl(std::string url_template, const std::string& id);
// Strict integer: digits only (optional sign), nothing after.
std::optional<std::int64_t> ParseInt(const std::string& text);
// Strict finite real number, nothing after.
std::optional<double> ParseReal(const std::string& text);

using Cells = std::vector<std::pair<std::string, Json>>;

// A cell's text: a JSON string as it is, anything else as JSON.
std::string CellText(const Json& v);

inline const std::vector<std::string> kVideoColumns = {"video", "path", "video_path", "url", "file"};
inline const std::vector<std::string> kIdColumns = {"id", "clip_id", "narration_id"};

// Fills `row` from named cells, or reports the first problem in `error`.
class RowBuilder {
 public:
  RowBuilder(const fs::path& list, const ListOptions& options, ListReadResult& out)
      : list_(list), base_(list.parent_path()), options_(options), out_(out) {}

  // What a column means, decided once per file from its header name.
  enum class Role { kVideo, kId, kStartFrame, kEndFrame, kStartTime, kEndTime, kStart, kEnd,
                    kMetadata };

  static Role RoleOf(const std::string& raw_key) {
    const std::string key = Lower(Trim(raw_key));
    auto in = [&key](const std::vector<std::string>& names) {
      return std::find(names.begin(), names.end(), key) != names.end();
    };
    if (in(kVideoColumns)) return Role::kVideo;
    if (in(kIdColumns)) return Role::kId;
    if (key == "start_frame") return Role::kStartFrame;
    if (key == "end_frame" || key == "stop_frame") return Role::kEndFrame;
    if (in({"start_time", "start_timestamp", "start_s"})) return Role::kStartTime;
    if (in({"end_time", "stop_timestamp", "end_s", "stop_time"})) return Role::kEndTime;
    if (key == "start") return Role::kStart;
    if (key == "end" || key == "stop") return Role::kEnd;
    return Role::kMetadata;
  }

  void Add(const Cells& cells, long line) {
    ListRow row;
    row.line = line;
    row.clip.source_list = list_.string();
    row.clip.source_line = line;
    std::optional<std::string> start_text, end_text;
    for (const auto& [raw_key, value] : cells) {
      auto [it, fresh] = roles_.emplace(raw_key, Role::kMetadata);
      if (fresh) it->second = RoleOf(raw_key);
      const Role role = it->second;
      if (role == Role::kMetadata) {
        if (Lower(Trim(raw_key)) == kObjectBoxColumn) {
          if (!ObjectBox(value, line, row)) return;
          continue;
        }
        row.clip.metadata[raw_key] = value;
        continue;
      }
      const std::string text = Trim(CellText(value));
      const std::string key = Lower(Trim(raw_key));
      switch (role) {
        case Role::kVideo: row.video = text; break;
        case Role::kId: row.clip.external_id = text; break;
        case Role::kStartFrame:
          if (!Frame(text, key, line, row.clip.start_frame)) return;
          break;
        case Role::kEndFrame:
          if (!Frame(text, key, line, row.clip.end_frame)) return;
          break;
        case Role::kStartTime:
          if (!Time(text, key, line, row.clip.start_s)) return;
          break;
        case Role::kEndTime:
          if (!Time(text, key, line, row.clip.end_s)) return;
          break;
        case Role::kStart: start_text = text; break;
        case Role::kEnd: end_text = text; break;
        case Role::kMetadata: break;
      }
    }
    if (start_text && !StartOrEnd(*start_text, "start", line, row.clip.start_frame,
                                  row.clip.start_s)) {
      return;
    }
    if (end_text && !StartOrEnd(*end_text, "end", line, row.clip.end_frame, row.clip.end_s)) {
      return;
    }
    Finish(std::move(row));
  }

  // A JSON object's members as cells.
  void AddObject(const Json& object, long line) {
    Cells cells;
    for (const auto& [k, v] : object.items()) cells.emplace_back(k, v);
    Add(cells, line);
  }

  // Shared final checks: video present and found, span ordered, no duplicate.
  void Finish(ListRow row) {
    const long line = row.line;
    if (row.video.empty()) return Bad(line, "video", "no video path or URL");
    if (!IsUrl(row.video)) {
      fs::path p(row.video);
      if (p.is_relative()) p = base_ / p;
      row.video = fs::absolute(p).lexically_normal().string();
      if (options_.check_files) {
        if (const std::string why = Unreachable(row.video); !why.empty()) {
          return Bad(line, "video", why);
        }
      }
    }
    const auto& c = row.clip;
    if (c.start_frame.has_value() != c.end_frame.has_value() && c.end_frame) {
      // an end without a start runs from the first frame
      row.clip.start_frame = 0;
    }
    if (c.start_frame && c.end_frame && *c.end_frame < *c.start_frame) {
      return Bad(line, "end_frame",
                 "end " + std::to_string(*c.end_frame) + " is before start " +
                     std::to_string(*c.start_frame));
    }
    if (c.start_s && c.end_s && *c.end_s < *c.start_s) {
      return Bad(line, "end_time", "end is before start");
    }
    if (const std::string why = PromptOutsideSpan(c); !why.empty()) {
      return Bad(line, kObjectBoxColumn, why);
    }
    char span[128];
    std::snprintf(span, sizeof span, "|%lld|%lld|%.17g|%.17g",
                  static_cast<long long>(c.start_frame.value_or(-1)),
                  static_cast<long long>(c.end_frame.value_or(-1)), c.start_s.value_or(-1),
                  c.end_s.value_or(-1));
    const auto [it, fresh] = seen_.emplace(row.video + span, line);
    if (!fresh) {
      return Bad(line, "video", "duplicate of line " + std::to_string(it->second) +
                                    " (same video and span)");
    }
    out_.rows.push_back(std::move(row));
  }

  void Bad(long line, const std::string& field, const std::string& reason) {
    out_.errors.push_back({list_.string(), line, field, reason});
  }

 private:
  // "" when the video file is there, else why not: a missing file, and the
  // file-system errors that must stay this row's (a symlink loop, a name
  // too long, no permission) rather than end the whole list.
  std::string Unreachable(const std::string& path) {
    auto [it, fresh] = unreachable_.emplace(path, "");
    if (!fresh) return it->second;
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec == std::errc::no_such_file_or_directory || (!ec && !fs::exists(st))) {
      it->second = "file not found: " + ShortPath(path);
    } else if (ec) {
      it->second = "cannot reach file (" + ec.message() + "): " + ShortPath(path);
    } else if (fs::is_directory(st)) {
      it->second = "a folder, not a video file: " + ShortPath(path);
    }
    return it->second;
  }

  // Keeps a message readable when a row names an absurdly long path.
  static std::string ShortPath(const std::string& path) {
    if (path.size() <= 300) return path;
    return path.substr(0, 120) + "...(" + std::to_string(path.size()) + " characters)..." +
           path.substr(path.size() - 60);
  }

  // The object prompt cell (ingest/object_prompt.h): kept under its one
  // name when well formed; an empty cell is no prompt.
  bool ObjectBox(const Json& value, long line, ListRow& row) {
    const std::string text = Trim(CellText(value));
    if (text.empty() || value.is_null()) return true;
    std::vector<ObjectPrompt> prompts;
    if (const std::string why = ParseObjectPrompts(text, &prompts); !why.empty()) {
      return Bad(line, kObjectBoxColumn, why), false;
    }
    row.clip.metadata[kObjectBoxColumn] = text;
    return true;
  }

  // Why a prompt's frame lies outside the row's frame span, or "".
  static std::string PromptOutsideSpan(const ClipRecord& c) {
    if (!c.metadata.is_object() || !c.metadata.contains(kObjectBoxColumn)) return "";
    std::vector<ObjectPrompt> prompts;
    ParseObjectPrompts(c.metadata[kObjectBoxColumn].get<std::string>(), &prompts);
    for (const ObjectPrompt& p : prompts) {
      if ((c.start_frame && p.frame < *c.start_frame) || (c.end_frame && p.frame > *c.end_frame)) {
        return "the box's frame " + std::to_string(p.frame) + " is outside the clip's frames " +
               std::to_string(c.start_frame.value_or(0)) + "-" +
               (c.end_frame ? std::to_string(*c.end_frame) : std::string("end"));
      }
    }
    return "";
  }

  bool Frame(const std::string& text, const std::string& field, long line,
             std::optional<std::int64_t>& out) {
    if (text.empty()) return true;
    const auto v = ParseInt(text);
    if (!v) return Bad(line, field, "not a whole frame number: '" + text + "'"), false;
    if (*v < 0) return Bad(line, field, "negative frame number " + text), false;
    if (*v > kMaxFrame) return Bad(line, field, "frame number out of range: " + text), false;
    out = *v;
    return true;
  }

  bool Time(const std::string& text, const std::string& field, long line,
            std::optional<double>& out) {
    if (text.empty()) return true;
    const auto v = ParseTimestamp(text);
    if (!v) return Bad(line, field, "not a time (seconds or HH:MM:SS.fff): '" + text + "'"), false;
    if (*v > kMaxSeconds) return Bad(line, field, "time out of range: " + text), false;
    out = *v;
    return true;
  }

  bool StartOrEnd(const std::string& text, const std::string& field, long line,
                  std::optional<std::int64_t>& frame, std::optional<double>& seconds) {
    if (ParseInt(text) || (!text.empty() && text[0] == '-' && ParseReal(text))) {
      return Frame(text, field, line, frame);
    }
    return Time(text, field, line, seconds);
  }

  fs::path list_;
  fs::path base_;
  const ListOptions& options_;
  ListReadResult& out_;
  std::unordered_map<std::string, long> seen_;
  std::unordered_map<std::string, Role> roles_;
  std::unordered_map<std::string, std::string> unreachable_;
};


}  // namespace doasido::ingest::rows
