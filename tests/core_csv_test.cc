// The one CSV reader (core/csv.h) against the cases RFC 4180 section 2
// lists, and the project's additions: a byte-order mark, blank lines,
// a quote that never closes, errors naming file, line and field, and a
// path that is not a regular file. The one writer against the same RFC,
// and read back by the reader field for field.
#include "core/csv.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <string>
#include <vector>

#include "core/error.h"
#include "core/error_codes.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using Rows = std::vector<std::vector<std::string>>;

// Every record of `text` after its header (or all of them), with lines.
Rows Records(const std::string& text, bool header = false, std::vector<long>* lines = nullptr,
             char delimiter = ',') {
  CsvReader reader(text, "t.csv", "bad_csv", delimiter);
  if (header) reader.Header();
  Rows rows;
  CsvRecord record;
  while (reader.Next(record)) {
    EXPECT_EQ(record.error, "") << "line " << record.line;
    rows.push_back(record.fields);
    if (lines) lines->push_back(record.line);
  }
  return rows;
}

// RFC 4180 2.1 and 2.2: records on separate lines ending in CRLF; the last
// line break is optional.
TEST(Csv, RecordsEndInCrlfAndTheLastLineBreakIsOptional) {
  const Rows expected = {{"aaa", "bbb", "ccc"}, {"zzz", "yyy", "xxx"}};
  EXPECT_EQ(Records("aaa,bbb,ccc\r\nzzz,yyy,xxx\r\n"), expected);
  EXPECT_EQ(Records("aaa,bbb,ccc\r\nzzz,yyy,xxx"), expected);
  EXPECT_EQ(Records("aaa,bbb,ccc\nzzz,yyy,xxx\n"), expected);  // LF files too
}

// 2.3: an optional header line with the same fields; Header() returns it
// trimmed and Next() starts after it.
TEST(Csv, TheHeaderIsTheFirstRecordAndTheRowsFollowIt) {
  CsvReader reader("field_name, field_name2 ,field_name3\r\naaa,bbb,ccc\r\n", "t.csv", "bad_csv");
  EXPECT_EQ(reader.Header(), (std::vector<std::string>{"field_name", "field_name2", "field_name3"}));
  EXPECT_EQ(reader.header_line(), 1);
  CsvRecord record;
  ASSERT_TRUE(reader.Next(record));
  EXPECT_EQ(record.fields, (std::vector<std::string>{"aaa", "bbb", "ccc"}));
  EXPECT_EQ(record.line, 2);
  EXPECT_FALSE(reader.Next(record));
}

// 2.4: spaces are part of a field; empty fields, a trailing comma's too.
TEST(Csv, SpacesArePartOfAFieldAndEmptyFieldsCount) {
  EXPECT_EQ(Records("aaa , bbb,ccc\n"), (Rows{{"aaa ", " bbb", "ccc"}}));
  EXPECT_EQ(Records("a,,c,\n"), (Rows{{"a", "", "c", ""}}));
}

// 2.5: fields may be enclosed in double quotes.
TEST(Csv, QuotedFieldsLoseTheirQuotes) {
  EXPECT_EQ(Records("\"aaa\",\"bbb\",\"ccc\"\r\nzzz,yyy,xxx\r\n"),
            (Rows{{"aaa", "bbb", "ccc"}, {"zzz", "yyy", "xxx"}}));
}

// 2.6: quoted fields hold line breaks and commas; the record after one
// that spans lines starts on the right line.
TEST(Csv, QuotedFieldsHoldLineBreaksAndCommas) {
  std::vector<long> lines;
  EXPECT_EQ(Records("\"aaa\",\"b\r\nbb\",\"c,c\"\r\nzzz,yyy,xxx\r\n", false, &lines),
            (Rows{{"aaa", "b\r\nbb", "c,c"}, {"zzz", "yyy", "xxx"}}));
  EXPECT_EQ(lines, (std::vector<long>{1, 3}));
}

// 2.7: a double quote inside a quoted field is written twice.
TEST(Csv, TwoQuotesInAQuotedFieldAreOne) {
  EXPECT_EQ(Records("\"aaa\",\"b\"\"bb\",\"ccc\"\n"), (Rows{{"aaa", "b\"bb", "ccc"}}));
  // A quote inside an unquoted field is an ordinary character.
  EXPECT_EQ(Records("a\"b,c\n"), (Rows{{"a\"b", "c"}}));
}

TEST(Csv, AByteOrderMarkAndBlankLinesBeforeTheHeaderAreSkipped) {
  CsvReader reader("\xEF\xBB\xBF\n  \nvideo,id\nv.mp4,1\n", "t.csv", "bad_csv");
  EXPECT_EQ(reader.Header(), (std::vector<std::string>{"video", "id"}));
  EXPECT_EQ(reader.header_line(), 3);
  CsvRecord record;
  ASSERT_TRUE(reader.Next(record));
  EXPECT_EQ(record.line, 4);
  EXPECT_FALSE(record.Blank());
}

TEST(Csv, TabSeparatedValuesUseTheSameRules) {
  EXPECT_EQ(Records("a\t\"b\tc\"\td\n", false, nullptr, '\t'), (Rows{{"a", "b\tc", "d"}}));
}

TEST(Csv, AnUnterminatedQuoteIsAnErrorOfItsRecordOnly) {
  CsvReader reader("a,b\n1,2\n3,\"open\n4,5\n", "t.csv", "bad_csv");
  reader.Header();
  CsvRecord record;
  ASSERT_TRUE(reader.Next(record));
  EXPECT_EQ(record.error, "");
  ASSERT_TRUE(reader.Next(record));
  EXPECT_EQ(record.error, "unterminated quoted field");
  EXPECT_EQ(record.line, 3);
  EXPECT_FALSE(reader.Next(record)) << "the quote ran to the end of the text";
}

TEST(Csv, ErrorsNameTheFileTheLineAndTheField) {
  CsvReader reader("\"a,b\n", "items.csv", "bad_csv");
  try {
    reader.Header();
    FAIL() << "an unterminated header was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_csv");
    EXPECT_EQ(e.site().file, "items.csv");
    EXPECT_EQ(e.site().line, 1);
    EXPECT_NE(e.message().find("header: unterminated quoted field"), std::string::npos);
  }
  try {
    reader.Fail(7, "item_id", "empty field");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.site().line, 7);
    EXPECT_EQ(e.site().field, "item_id");
  }
  EXPECT_THROW(CsvReader(" \n\n", "blank.csv", "bad_csv").Header(), Error);
}

TEST(Csv, APathThatIsNotARegularFileIsNotOpened) {
  testing::TempDir dir;
  const auto fifo = dir / "list.csv";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  try {
    CsvReader::Open(fifo, "bad_csv");  // a FIFO would block a reader forever
    FAIL() << "a FIFO was opened";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), kNotARegularFile);
  }
  try {
    CsvReader::Open(dir / "absent.csv", "bad_csv");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_csv");
    EXPECT_EQ(e.site().file, (dir / "absent.csv").string());
  }
}

TEST(Csv, ColumnsAreFoundByName) {
  const std::vector<std::string> header = {"video", "id"};
  EXPECT_EQ(CsvColumn(header, "id"), 1u);
  EXPECT_EQ(CsvColumn(header, "fps"), header.size());
  EXPECT_EQ(TrimCsvField(" \tx y\r\n"), "x y");
  EXPECT_EQ(TrimCsvField("  "), "");
}

// RFC 4180 2.6 and 2.7: a field holding a comma, a quote or a line break is
// quoted and its quotes doubled; any other field is written as it is.
TEST(Csv, TheWriterQuotesOnlyWhatNeedsIt) {
  EXPECT_EQ(CsvField("plain"), "plain");
  EXPECT_EQ(CsvField(""), "");
  EXPECT_EQ(CsvField(" spaced "), " spaced ");
  EXPECT_EQ(CsvField("a,b"), "\"a,b\"");
  EXPECT_EQ(CsvField("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(CsvField("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(CsvField("cr\r"), "\"cr\r\"");
  EXPECT_EQ(CsvLine({"aaa", "b\"bb", "ccc"}), "aaa,\"b\"\"bb\",ccc\n");
  EXPECT_EQ(CsvLine({}), "\n");
}

// What the writer writes the reader reads back, field for field: commas,
// quotes, line ends (LF and CRLF inside a field), empty fields at either
// end, white space kept, a field that is only a quote.
TEST(Csv, WrittenRecordsReadBackEqual) {
  const Rows written = {{"name", "note", "n"},
                        {"plain", "", "1"},
                        {"", "a,b", ""},
                        {"say \"hi\"", "\"", "\"\""},
                        {"two\nlines", "cr\r\nlf", ",,"},
                        {"  lead", "trail  ", " \"quoted\" "}};
  std::string text;
  for (const auto& row : written) text += CsvLine(row);
  std::vector<long> lines;
  EXPECT_EQ(Records(text, false, &lines), written);
  EXPECT_EQ(lines, (std::vector<long>{1, 2, 3, 4, 5, 8}));
}

}  // namespace
}  // namespace doasido
