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
#include "ingest/list_rows.h"

namespace doasido::ingest {
namespace {

namespace fs = std::filesystem;
using namespace rows;  // NOLINT: the row helpers are this file's vocabulary

// A clip object is a flat record with a little nested metadata; a list of
// JSON is at most the size of a large dataset's index.
constexpr JsonLimits kRowLimits{.max_depth = 32, .max_bytes = 1u << 20};
constexpr JsonLimits kDocumentLimits{.max_depth = 32, .max_bytes = 1u << 30};

std::string ReadAll(const fs::path& path) {
  return ReadFileOrThrow(path, "bad_list", "cannot open list");
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

// The steps of ReadVoc.

// The annotation folder (`folder`/Annotations when there is one) and its
// *.xml files, sorted.
fs::path VocFiles(const fs::path& folder, std::vector<fs::path>& files) {
  std::error_code ec;
  const fs::path annotations =
      fs::is_directory(folder / "Annotations", ec) ? folder / "Annotations" : folder;
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
  return annotations;
}

// One <object> of a VOC file as a detection `d` of `frame`; else the field
// and why it cannot be one.
std::pair<std::string, std::string> VocDetection(const tinyxml2::XMLElement* obj,
                                                 std::int64_t frame, const ImageSize& image,
                                                 Detection& d) {
  const auto* kind = obj->FirstChildElement("name");
  const auto* box = obj->FirstChildElement("bndbox");
  if (kind == nullptr || kind->GetText() == nullptr || box == nullptr) {
    return {"object", "object without <name> or <bndbox>"};
  }
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
  const std::string why =
      !numbers_ok ? "box numbers are missing or not numbers" : ImpossibleBox(d, image);
  if (!why.empty()) return {"bndbox", why};
  return {};
}

void ReadVoc(const fs::path& folder, const ListOptions& options, ListReadResult& out) {
  std::vector<fs::path> files;
  const fs::path annotations = VocFiles(folder, files);
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
      Detection d;
      if (const auto [field, why] = VocDetection(obj, frame, image_size, d); !why.empty()) {
        ok = false;
        bad(field, why);
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
