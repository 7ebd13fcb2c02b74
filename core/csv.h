// The one reader of delimited text (CSV, TSV) in the project: clip lists,
// EPIC-KITCHENS tables, study items, keypoint CSVs and HOT3D pose tables all
// go through it, so a quoted comma, a CRLF file or a byte-order mark means
// the same everywhere. And the one writer (CsvField, CsvLine): the report's
// tables, the synthetic clip list and trajectory CSVs, which the reader reads
// back field for field.
//
// RFC 4180 quoting: a field that begins (after white space) with a double
// quote runs to the closing quote and may hold the delimiter, line ends and
// "" for one quote; a quote inside an unquoted field is an ordinary
// character. Lines end in LF or CRLF (the CR of an unquoted field's end is
// dropped). A UTF-8 byte-order mark at the start of the text is removed.
// Fields are returned as written (not trimmed): callers decide whether
// white space matters.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace doasido {

// One record: its fields, where it starts and its text.
struct CsvRecord {
  std::vector<std::string> fields;
  long line = 0;      // the line it starts on, 1 for the first
  std::string raw;    // its bytes, line end included
  std::string error;  // not empty: malformed (an unterminated quote)

  // Only white space (an empty line, or spaces and tabs).
  bool Blank() const;
};

class CsvReader {
 public:
  // Over `text` read from `file` (named in every error, which carries
  // `code`).
  CsvReader(std::string text, std::string file, std::string code, char delimiter = ',');

  // Reads `path` whole. A path that is not a regular file (a FIFO or a
  // device may never end) is refused without being opened:
  // Error(kNotARegularFile); one that cannot be read: Error(code, "cannot
  // read").
  static CsvReader Open(const std::filesystem::path& path, const std::string& code,
                        char delimiter = ',');

  // The header: the first record that is not blank, its fields trimmed of
  // white space. Throws Error(code) naming the file and line for an
  // unterminated quote ("header: ..."), and for a text with no header.
  std::vector<std::string> Header();

  // The next record after the header (or from the start when Header() was
  // not called); false at the end of the text. A malformed record comes
  // back with `error` set and the reader goes on after it.
  bool Next(CsvRecord& record);

  // Throws Error(code, message) naming the file, `line` and `field`.
  [[noreturn]] void Fail(long line, const std::string& field, const std::string& message) const;

  const std::string& file() const { return file_; }
  // The line the header stands on (after Header()).
  long header_line() const { return header_line_; }

 private:
  std::string text_;
  std::string file_;
  std::string code_;
  char delimiter_;
  std::size_t pos_ = 0;
  long line_ = 1;
  long header_line_ = 0;
};

// `field` as one field of a CSV record (RFC 4180): quoted when it holds a
// comma, a double quote or a line break (CR or LF), each inner quote
// doubled; unchanged otherwise, so plain fields are written as they are.
std::string CsvField(const std::string& field);

// One record: `fields` through CsvField, joined by commas, ending in LF.
std::string CsvLine(const std::vector<std::string>& fields);

// `text` without leading and trailing spaces, tabs, CRs and LFs.
std::string TrimCsvField(const std::string& text);

// The index of the column named `name` in `header`, or header.size() when
// there is none.
std::size_t CsvColumn(const std::vector<std::string>& header, const std::string& name);

}  // namespace doasido
