#include "core/csv.h"

#include <algorithm>
#include <utility>

#include "core/error.h"
#include "core/error_codes.h"
#include "core/file_text.h"

namespace doasido {
namespace {

constexpr const char* kByteOrderMark = "\xEF\xBB\xBF";

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

bool AllSpace(const std::string& s) { return std::all_of(s.begin(), s.end(), IsSpace); }

// Splits the record starting at `pos`, advancing `pos` past its line end;
// quoted fields may span lines. Returns false with `error` set for an
// unterminated quote (then `pos` is the end of the text).
bool SplitRecord(const std::string& text, std::size_t& pos, char delimiter,
                 std::vector<std::string>& fields, std::string& error, long& lines_consumed) {
  fields.clear();
  lines_consumed = 0;
  std::string field;
  bool quoted = false, was_quoted = false;
  while (pos < text.size()) {
    const char c = text[pos];
    if (quoted) {
      if (c == '"') {
        if (pos + 1 < text.size() && text[pos + 1] == '"') {
          field += '"';
          pos += 2;
          continue;
        }
        quoted = false;
      } else {
        if (c == '\n') ++lines_consumed;
        field += c;
      }
      ++pos;
      continue;
    }
    if (c == '"' && AllSpace(field) && !was_quoted) {
      quoted = was_quoted = true;
      field.clear();
    } else if (c == delimiter) {
      fields.push_back(std::move(field));
      field.clear();
      was_quoted = false;
    } else if (c == '\n') {
      ++pos;
      ++lines_consumed;
      if (!field.empty() && field.back() == '\r') field.pop_back();
      fields.push_back(std::move(field));
      return true;
    } else {
      field += c;
    }
    ++pos;
  }
  if (quoted) {
    error = "unterminated quoted field";
    ++lines_consumed;
    return false;
  }
  if (!field.empty() && field.back() == '\r') field.pop_back();
  fields.push_back(std::move(field));
  ++lines_consumed;
  return true;
}

}  // namespace

bool CsvRecord::Blank() const { return AllSpace(raw); }

CsvReader::CsvReader(std::string text, std::string file, std::string code, char delimiter)
    : text_(std::move(text)), file_(std::move(file)), code_(std::move(code)), delimiter_(delimiter) {
  if (text_.rfind(kByteOrderMark, 0) == 0) pos_ = 3;
}

CsvReader CsvReader::Open(const std::filesystem::path& path, const std::string& code,
                          char delimiter) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!ec && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
    throw Error(kNotARegularFile, "not a regular file: it may never end, so it is not opened",
                {.file = path.string()});
  }
  return CsvReader(ReadFileOrThrow(path, code, "cannot read"), path.string(), code, delimiter);
}

std::vector<std::string> CsvReader::Header() {
  CsvRecord record;
  while (Next(record)) {
    if (!record.error.empty()) Fail(record.line, "", "header: " + record.error);
    if (record.Blank()) continue;
    for (std::string& name : record.fields) name = TrimCsvField(name);
    header_line_ = record.line;
    return record.fields;
  }
  throw Error(code_, "empty (no header)", {.file = file_});
}

bool CsvReader::Next(CsvRecord& record) {
  if (pos_ >= text_.size()) return false;
  const std::size_t start = pos_;
  long consumed = 0;
  record.line = line_;
  record.error.clear();
  SplitRecord(text_, pos_, delimiter_, record.fields, record.error, consumed);
  line_ += consumed;
  record.raw.assign(text_, start, pos_ - start);
  return true;
}

void CsvReader::Fail(long line, const std::string& field, const std::string& message) const {
  throw Error(code_, message, {.file = file_, .line = line, .field = field});
}

std::string CsvField(const std::string& field) {
  if (field.find_first_of(",\"\r\n") == std::string::npos) return field;
  std::string out = "\"";
  for (char c : field) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string CsvLine(const std::vector<std::string>& fields) {
  std::string out;
  for (std::size_t i = 0; i < fields.size(); ++i) out += (i ? "," : "") + CsvField(fields[i]);
  return out + "\n";
}

std::string TrimCsvField(const std::string& text) {
  const auto b = std::find_if_not(text.begin(), text.end(), IsSpace);
  const auto e = std::find_if_not(text.rbegin(), text.rend(), IsSpace).base();
  return b < e ? std::string(b, e) : std::string();
}

std::size_t CsvColumn(const std::vector<std::string>& header, const std::string& name) {
  return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
}

}  // namespace doasido
