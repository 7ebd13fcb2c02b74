#include "ingest/clip_list.h"

#include <tinyxml2.h>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <unordered_map>

#include "core/csv.h"
#include "core/file_text.h"
#include "core/error.h"
#include "core/error_codes.h"
#include "core/json_input.h"

namespace doasido::ingest {
namespace {

namespace fs = std::filesystem;

constexpr std::int64_t kMaxFrame = 1'000'000'000;  // ~1 year at 30 fps
// A clip object is a flat record with a little nested metadata; a list of
// JSON is at most the size of a large dataset's index.
constexpr JsonLimits kRowLimits{.max_depth = 32, .max_bytes = 1u << 20};
constexpr JsonLimits kDocumentLimits{.max_depth = 32, .max_bytes = 1u << 30};
constexpr double kMaxSeconds = 1e7;                 // ~115 days

std::string ReadAll(const fs::path& path) {
  return ReadFileOrThrow(path, "bad_list", "cannot open list");
}

bool IsUtf8(const std::string& s) {
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    size_t extra = 0;
    if (c < 0x80) {
      extra = 0;
    } else if (c >= 0xC2 && c <= 0xDF) {
      extra = 1;
    } else if ((c >> 4) == 0xE) {
      extra = 2;
    } else if (c >= 0xF0 && c <= 0xF4) {
      extra = 3;
    } else {
      return false;
    }
    if (i + extra >= s.size() && extra > 0) return false;
    for (size_t k = 1; k <= extra; ++k) {
      if ((static_cast<unsigned char>(s[i + k]) >> 6) != 0x2) return false;
    }
    i += 1 + extra;
  }
  return true;
}

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool IsUrl(const std::string& s) { return s.find("://") != std::string::npos; }

std::string VideoUrl(std::string url_template, const std::string& id) {
  for (auto pos = url_template.find("{id}"); pos != std::string::npos;
       pos = url_template.find("{id}", pos + id.size())) {
    url_template.replace(pos, 4, id);
  }
  return url_template;
}

// Only white space (or nothing): the same empty list in every format.
bool IsBlank(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char c = 0;
  while (in.get(c)) {
    if (!std::isspace(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

[[noreturn]] void NotAList(const fs::path& path, const std::string& what) {
  throw Error("not_a_clip_list",
              what + "; expected a clip list: CSV/TSV with a header naming a video column, "
                     "JSON Lines of clip objects, a JSON array of clip objects, a JSON object "
                     "mapping video ids to metadata objects ({\"<youtubeId>\": {\"fps\": ...}}), "
                     "an EPIC-KITCHENS CSV, a 100DOH VOC folder or a text file of 100DOH frame "
                     "names",
              {.file = path.string()});
}

// Strict integer: digits only (optional sign), nothing after.
std::optional<std::int64_t> ParseInt(const std::string& text) {
  const std::string t = Trim(text);
  if (t.empty()) return std::nullopt;
  std::int64_t v = 0;
  const char* begin = t.data() + (t[0] == '+' ? 1 : 0);
  const auto [ptr, ec] = std::from_chars(begin, t.data() + t.size(), v);
  if (ec != std::errc() || ptr != t.data() + t.size()) return std::nullopt;
  return v;
}

std::optional<double> ParseReal(const std::string& text) {
  const std::string t = Trim(text);
  if (t.empty()) return std::nullopt;
  double v = 0;
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec != std::errc() || ptr != t.data() + t.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

using Cells = std::vector<std::pair<std::string, Json>>;

std::string CellText(const Json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

const std::vector<std::string> kVideoColumns = {"video", "path", "video_path", "url", "file"};
const std::vector<std::string> kIdColumns = {"id", "clip_id", "narration_id"};

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

// Why a record of a delimited list is not a row ("" when it is one): an
// unterminated quote, an empty line, bytes that are not UTF-8 text, or
// another number of columns than the header's.
std::string RecordProblem(const CsvRecord& record, size_t columns) {
  if (!record.error.empty()) return record.error;
  if (record.Blank()) return "empty line";
  if (!IsUtf8(record.raw)) return "not valid UTF-8 text";
  if (record.fields.size() != columns) {
    return "expected " + std::to_string(columns) + " columns, found " +
           std::to_string(record.fields.size());
  }
  return "";
}

void ReadDelimited(const fs::path& path, char delimiter, const ListOptions& options,
                   ListReadResult& out) {
  CsvReader reader(ReadAll(path), path.string(), "bad_list", delimiter);
  const std::vector<std::string> header = reader.Header();
  const bool has_video = std::any_of(header.begin(), header.end(), [](const std::string& h) {
    return std::find(kVideoColumns.begin(), kVideoColumns.end(), Lower(h)) != kVideoColumns.end();
  });
  if (!has_video) {
    throw Error("bad_list", "no video column (one of video, path, video_path, url, file)",
                {.file = path.string(), .line = 1, .field = "header"});
  }
  RowBuilder builder(path, options, out);
  Cells cells;
  CsvRecord record;
  while (reader.Next(record)) {
    if (const std::string why = RecordProblem(record, header.size()); !why.empty()) {
      const std::size_t found = record.fields.size();
      const bool short_row = record.error.empty() && !record.Blank() && IsUtf8(record.raw) &&
                             found < header.size();
      builder.Bad(record.line, short_row ? header[found] : "", why);
      continue;
    }
    cells.clear();
    for (size_t i = 0; i < header.size(); ++i) cells.emplace_back(header[i], record.fields[i]);
    builder.Add(cells, record.line);
  }
}

void ReadJsonLines(const fs::path& path, const ListOptions& options, ListReadResult& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("bad_list", "cannot open list", {.file = path.string()});
  RowBuilder builder(path, options, out);
  std::string text;
  long line = 0, objects = 0;
  while (std::getline(in, text)) {
    ++line;
    if (Trim(text).empty()) {
      builder.Bad(line, "", "empty line");
      continue;
    }
    if (!IsUtf8(text)) {
      builder.Bad(line, "", "not valid UTF-8 text");
      continue;
    }
    Json obj;
    try {
      obj = ParseJsonInput(text, {}, kRowLimits);
    } catch (const Error& e) {
      builder.Bad(line, "", e.code() + ": " + e.message());
      continue;
    }
    if (!obj.is_object()) {
      builder.Bad(line, "", "not a JSON object");
      continue;
    }
    ++objects;
    builder.AddObject(obj, line);
  }
  if (objects == 0) NotAList(path, "no line is a JSON object");
}

// One JSON document: an array of clip objects, or an object mapping video
// ids to metadata objects. Returns false when the text is not one JSON
// document (then it may be JSON Lines).
bool ReadJsonDocument(const fs::path& path, const ListOptions& options, ListReadResult& out) {
  Json doc;
  try {
    doc = ParseJsonInput(ReadAll(path), {.file = path.string()}, kDocumentLimits);
  } catch (const Error& e) {
    if (e.code() == kJsonTooLarge) throw;
    return false;  // JSON Lines, perhaps; its reader names the bad lines
  }
  RowBuilder builder(path, options, out);
  Cells cells;
  if (doc.is_array()) {
    out.format = "json";
    long index = 0, objects = 0;
    for (const Json& item : doc) {
      ++index;
      if (!item.is_object()) {
        builder.Bad(index, "", "array item is not a JSON object");
        continue;
      }
      ++objects;
      builder.AddObject(item, index);
    }
    if (objects == 0) NotAList(path, "a JSON array without clip objects");
    return true;
  }
  if (doc.is_object() && std::any_of(kVideoColumns.begin(), kVideoColumns.end(),
                                     [&doc](const std::string& k) { return doc.contains(k); })) {
    return false;  // a one-line JSON Lines file: one clip
  }
  if (!doc.is_object() || doc.empty()) NotAList(path, "a JSON document that is not an id map");
  for (const auto& [id, fields] : doc.items()) {
    if (!fields.is_object()) {
      NotAList(path, "a JSON object whose value at \"" + id + "\" is not an object");
    }
  }
  out.format = "idmap";
  const std::string url_template =
      options.video_url_template.empty() ? kYoutubeUrlTemplate : options.video_url_template;
  long index = 0;
  for (const auto& [id, fields] : doc.items()) {
    ++index;
    cells.clear();
    cells.emplace_back("video", VideoUrl(url_template, id));
    cells.emplace_back("id", id);
    for (const auto& [k, v] : fields.items()) cells.emplace_back(k, v);
    builder.Add(cells, index);
  }
  return true;
}

// Reads a CSV into header-named rows (for EPIC's two files).
std::vector<std::map<std::string, std::string>> ReadTable(const fs::path& path,
                                                         std::vector<RowError>* errors,
                                                         std::vector<long>* lines) {
  CsvReader reader(ReadAll(path), path.string(), "bad_list");
  const std::vector<std::string> header = reader.Header();
  std::vector<std::map<std::string, std::string>> rows;
  CsvRecord record;
  while (reader.Next(record)) {
    if (const std::string why = RecordProblem(record, header.size()); !why.empty()) {
      if (errors) errors->push_back({path.string(), record.line, "", why});
      continue;
    }
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < header.size(); ++i) row[header[i]] = record.fields[i];
    rows.push_back(std::move(row));
    if (lines) lines->push_back(record.line);
  }
  return rows;
}

void ReadEpic(const fs::path& path, const ListOptions& options, ListReadResult& out) {
  const fs::path info_path = options.epic_video_info.empty()
                                 ? path.parent_path() / "EPIC_100_video_info.csv"
                                 : options.epic_video_info;
  if (!fs::exists(info_path)) {
    throw Error("bad_list", "EPIC list needs its video info CSV (--video-info)",
                {.file = info_path.string()});
  }
  std::map<std::string, std::map<std::string, std::string>> info;
  for (auto& row : ReadTable(info_path, nullptr, nullptr)) info[row["video_id"]] = row;
  const fs::path root =
      options.epic_video_root.empty() ? path.parent_path() / "videos" : options.epic_video_root;
  ListOptions no_check = options;
  no_check.check_files = false;  // EPIC lists come without their footage
  RowBuilder builder(path, no_check, out);
  std::vector<long> lines;
  const auto rows = ReadTable(path, &out.errors, &lines);
  const std::vector<std::string> used = {"narration_id", "participant_id", "video_id",
                                         "start_timestamp", "stop_timestamp", "start_frame",
                                         "stop_frame"};
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    const long line = lines[i];
    auto get = [&r](const std::string& k) {
      const auto it = r.find(k);
      return it == r.end() ? std::string() : it->second;
    };
    const auto video_info = info.find(get("video_id"));
    if (video_info == info.end()) {
      builder.Bad(line, "video_id", "'" + get("video_id") + "' is not in " + info_path.string());
      continue;
    }
    Cells cells = {{"narration_id", get("narration_id")},
                   {"video", (root / get("participant_id") / "videos" /
                              (get("video_id") + ".MP4")).string()},
                   {"start_frame", get("start_frame")},
                   {"stop_frame", get("stop_frame")},
                   {"start_timestamp", get("start_timestamp")},
                   {"stop_timestamp", get("stop_timestamp")}};
    for (const auto& [k, v] : r) {
      if (std::find(used.begin(), used.end(), k) == used.end()) cells.emplace_back(k, v);
    }
    cells.emplace_back("participant_id", get("participant_id"));
    cells.emplace_back("video_id", get("video_id"));
    const auto fps = ParseReal(video_info->second["fps"]);
    if (fps) cells.emplace_back("fps", *fps);
    cells.emplace_back("resolution", video_info->second["resolution"]);
    // EPIC numbers frames at 60 per second whatever the video's real rate
    // (29.97, 47.95, 59.94 and 90 fps videos alike), so a frame number is
    // not a frame index into the video: decode by time, or scale.
    cells.emplace_back("frame_numbers_fps", 60);
    builder.Add(cells, line);
  }
}

struct FrameGroup {
  std::string genre;
  std::map<std::int64_t, std::vector<Detection>> frames;
  long first_index = 0;
};

double Number(const tinyxml2::XMLElement* parent, const char* name, bool* ok) {
  const auto* e = parent->FirstChildElement(name);
  if (e == nullptr || e->GetText() == nullptr) return 0;
  const std::string text = Trim(e->GetText());
  if (text.empty() || text == "None") return 0;
  const auto v = ParseReal(text);
  if (!v) *ok = false;
  return v.value_or(0);
}

// Why a VOC box cannot be true ("" when it can): empty or reversed, or
// reaching past the image (given by the file's <size>, when it has one) by
// more than annotators' rounding.
struct ImageSize {
  double width = 0, height = 0;  // 0 when the file does not say
};

std::string ImpossibleBox(const Detection& d, const ImageSize& image) {
  char text[160];
  const auto say = [&](const char* what) {
    std::snprintf(text, sizeof text, "%s: xmin %g ymin %g xmax %g ymax %g (image %gx%g)", what,
                  d.x1 + 1, d.y1 + 1, d.x2, d.y2, image.width, image.height);
    return std::string(text);
  };
  if (d.x2 <= d.x1 || d.y2 <= d.y1) return say("empty or reversed box");
  if (image.width <= 0 || image.height <= 0) return "";
  const double slack_x = std::max(2.0, 0.01 * image.width);
  const double slack_y = std::max(2.0, 0.01 * image.height);
  if (d.x1 < -slack_x || d.y1 < -slack_y || d.x2 > image.width + slack_x ||
      d.y2 > image.height + slack_y) {
    return say("box outside the image");
  }
  return "";
}

// Adds the rows of grouped frames (VOC folders and frame-name lists).
void AddFrameGroups(const std::map<std::string, FrameGroup>& groups, const fs::path& list,
                    const fs::path& video_dir, const ListOptions& options, ListReadResult& out) {
  ListOptions no_check = options;
  no_check.check_files = false;  // the annotations are the data; probe reports missing videos
  RowBuilder builder(list, no_check, out);
  for (const auto& [video, group] : groups) {
    ListRow row;
    row.line = group.first_index;
    row.video = (video_dir / (video + ".mp4")).string();
    std::error_code ec;
    if (!options.video_url_template.empty() && !fs::exists(row.video, ec)) {
      row.video = VideoUrl(options.video_url_template, video);
    }
    row.clip.external_id = group.genre.empty() ? video : group.genre + "_v_" + video;
    row.clip.source_list = list.string();
    row.clip.source_line = group.first_index;
    row.clip.start_frame = group.frames.begin()->first;
    row.clip.end_frame = group.frames.rbegin()->first;
    row.clip.metadata["genre"] = group.genre;
    row.clip.metadata["annotated_frames"] = group.frames.size();
    for (const auto& [frame, dets] : group.frames) {
      row.detections.insert(row.detections.end(), dets.begin(), dets.end());
    }
    builder.Finish(std::move(row));
  }
}

void ReadVoc(const fs::path& folder, const ListOptions& options, ListReadResult& out) {
  std::error_code ec;
  const fs::path annotations =
      fs::is_directory(folder / "Annotations", ec) ? folder / "Annotations" : folder;
  std::vector<fs::path> files;
  for (fs::directory_iterator it(annotations, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->path().extension() == ".xml") files.push_back(it->path());
  }
  if (ec) {
    throw Error("bad_list", "cannot read the annotation folder: " + ec.message(),
                {.file = annotations.string()});
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    throw Error("bad_list", "no *.xml annotations", {.file = annotations.string()});
  }
  std::map<std::string, FrameGroup> groups;
  long index = 0;
  for (const auto& file : files) {
    ++index;
    auto bad = [&](const std::string& field, const std::string& reason) {
      out.errors.push_back({file.string(), 0, field, reason});
    };
    const auto name = ParseFrameName(file.stem().string());
    if (!name) {
      bad("filename", "not <genre>_v_<video>_frame<digits>");
      continue;
    }
    tinyxml2::XMLDocument doc;
    if (doc.LoadFile(file.c_str()) != tinyxml2::XML_SUCCESS) {
      bad("xml", std::string("malformed XML: ") + doc.ErrorStr());
      continue;
    }
    const auto* root = doc.FirstChildElement("annotation");
    if (root == nullptr) {
      bad("annotation", "no <annotation> element");
      continue;
    }
    const auto frame =
        static_cast<std::int64_t>(std::llround(name->frame * options.voc_frame_scale));
    auto& group = groups[name->video];
    if (group.frames.empty() && group.first_index == 0) group.first_index = index;
    group.genre = name->genre;
    auto& dets = group.frames[frame];
    bool ok = true;
    bool size_ok = true;
    const auto* size = root->FirstChildElement("size");
    const ImageSize image_size =
        size ? ImageSize{Number(size, "width", &size_ok), Number(size, "height", &size_ok)}
             : ImageSize{};
    for (const auto* obj = root->FirstChildElement("object"); obj;
         obj = obj->NextSiblingElement("object")) {
      const auto* kind = obj->FirstChildElement("name");
      const auto* box = obj->FirstChildElement("bndbox");
      if (kind == nullptr || kind->GetText() == nullptr || box == nullptr) {
        ok = false;
        bad("object", "object without <name> or <bndbox>");
        break;
      }
      Detection d;
      d.frame = frame;
      d.source = "100doh_voc";
      const std::string k = Trim(kind->GetText());
      d.kind = k == "hand" ? "hand" : "object";
      bool numbers_ok = true;
      // VOC boxes are 1-based inclusive; ours are 0-based with exclusive ends.
      d.x1 = Number(box, "xmin", &numbers_ok) - 1;
      d.y1 = Number(box, "ymin", &numbers_ok) - 1;
      d.x2 = Number(box, "xmax", &numbers_ok);
      d.y2 = Number(box, "ymax", &numbers_ok);
      if (d.kind == "hand") {
        d.contact_state = static_cast<int>(Number(obj, "contactstate", &numbers_ok));
        d.hand_side = static_cast<int>(Number(obj, "handside", &numbers_ok));
        d.dx = Number(obj, "unitdx", &numbers_ok);
        d.dy = Number(obj, "unitdy", &numbers_ok);
        d.magnitude = Number(obj, "magnitude", &numbers_ok);
      }
      const std::string why = !numbers_ok ? "box numbers are missing or not numbers"
                                          : ImpossibleBox(d, image_size);
      if (!why.empty()) {
        ok = false;
        bad("bndbox", why);
        break;
      }
      dets.push_back(d);
    }
    if (!ok) group.frames.erase(frame);
    if (group.frames.empty()) groups.erase(name->video);
  }
  const fs::path video_dir = options.voc_video_dir.empty()
                                 ? annotations.parent_path() / "videos"
                                 : options.voc_video_dir;
  AddFrameGroups(groups, folder, video_dir, options, out);
}

void ReadFrameNames(const fs::path& path, const ListOptions& options, ListReadResult& out) {
  std::ifstream in(path);
  if (!in) throw Error("bad_list", "cannot open list", {.file = path.string()});
  std::map<std::string, FrameGroup> groups;
  std::string text;
  long line = 0;
  while (std::getline(in, text)) {
    ++line;
    const auto name = ParseFrameName(Trim(text));
    if (!name) {
      out.errors.push_back({path.string(), line, "name",
                            Trim(text).empty() ? "empty line" : "not a 100DOH frame name"});
      continue;
    }
    const std::string key = name->split.empty() ? name->video : name->genre + "_" + name->video;
    auto& group = groups[key];
    if (group.frames.empty()) group.first_index = line;
    group.genre = name->genre;
    group.frames[static_cast<std::int64_t>(std::llround(name->frame * options.voc_frame_scale))];
  }
  if (groups.empty()) NotAList(path, "no line is a 100DOH frame name");
  const fs::path video_dir =
      options.voc_video_dir.empty() ? path.parent_path() / "videos" : options.voc_video_dir;
  AddFrameGroups(groups, path, video_dir, options, out);
}

}  // namespace

std::string RowError::Format() const {
  return file + ":" + std::to_string(line) + ": " + (field.empty() ? "" : field + ": ") + reason;
}

std::optional<double> ParseTimestamp(const std::string& raw) {
  const std::string text = Trim(raw);
  if (text.empty()) return std::nullopt;
  std::vector<std::string> parts;
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, ':')) parts.push_back(part);
  if (parts.empty() || parts.size() > 3) return std::nullopt;
  double total = 0;
  for (size_t i = 0; i < parts.size(); ++i) {
    const bool last = i + 1 == parts.size();
    std::optional<double> v = ParseReal(parts[i]);
    if (!last) {
      const auto whole = ParseInt(parts[i]);
      v = whole ? std::optional<double>(static_cast<double>(*whole)) : std::nullopt;
    }
    if (!v || *v < 0) return std::nullopt;
    if (i > 0 && *v >= 60) return std::nullopt;  // minutes and seconds fields
    total = total * 60 + *v;
  }
  if (!std::isfinite(total)) return std::nullopt;
  return total;
}

std::optional<FrameName> ParseFrameName(const std::string& name) {
  FrameName out;
  const auto v = name.find("_v_");
  const auto f = name.rfind("_frame");
  if (v != std::string::npos && f != std::string::npos && f > v + 3) {
    const auto frame = ParseInt(name.substr(f + 6));
    if (!frame || *frame < 0 || name.size() - (f + 6) == 0) return std::nullopt;
    out.genre = name.substr(0, v);
    out.video = name.substr(v + 3, f - v - 3);
    out.frame = *frame;
    return out.genre.empty() ? std::nullopt : std::optional(out);
  }
  // Egocentric: <dataset>_<split>_<video>_<digits>; the video id may hold '_'.
  const auto first = name.find('_');
  const auto second = first == std::string::npos ? first : name.find('_', first + 1);
  const auto last = name.rfind('_');
  if (second == std::string::npos || last <= second + 1) return std::nullopt;
  const auto frame = ParseInt(name.substr(last + 1));
  if (!frame || *frame < 0) return std::nullopt;
  out.genre = name.substr(0, first);
  out.split = name.substr(first + 1, second - first - 1);
  out.video = name.substr(second + 1, last - second - 1);
  out.frame = *frame;
  return out;
}

ListReadResult ReadClipList(const fs::path& given, const ListOptions& options) {
  // Relative paths in a list are relative to the list's folder; anchoring
  // the list itself first keeps that true from any working directory.
  const fs::path path = fs::absolute(given).lexically_normal();
  ListReadResult out;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) {
    throw Error("bad_list", ec ? ec.message() : "no such file or folder", {.file = path.string()});
  }
  if (fs::is_directory(status)) {
    out.format = "voc";
    ReadVoc(path, options, out);
    return out;
  }
  if (!fs::is_regular_file(status)) {
    throw Error(kNotARegularFile, "a list is a file or a VOC folder; this one may never end",
                {.file = path.string()});
  }
  if (IsBlank(path)) {
    throw Error(kEmptyList, "the list is empty (no header, no rows): nothing to ingest",
                {.file = path.string()});
  }
  const std::string ext = Lower(path.extension().string());
  if (ext == ".json" && ReadJsonDocument(path, options, out)) return out;
  if (ext == ".jsonl" || ext == ".json" || ext == ".ndjson") {
    out.format = "jsonl";
    ReadJsonLines(path, options, out);
  } else if (ext == ".tsv") {
    out.format = "tsv";
    ReadDelimited(path, '\t', options, out);
  } else if (ext == ".txt") {
    out.format = "framenames";
    ReadFrameNames(path, options, out);
  } else {
    std::ifstream in(path);
    std::string first;
    std::getline(in, first);
    if (first.rfind("narration_id", 0) == 0) {
      out.format = "epic";
      ReadEpic(path, options, out);
    } else {
      out.format = "csv";
      ReadDelimited(path, ',', options, out);
    }
  }
  return out;
}

}  // namespace doasido::ingest
