// Commands that only look at a database (status, queue, report, review)
// refuse a missing file instead of creating an empty one, and every command
// refuses another program's SQLite file without writing to it (doasido marks
// its files with SQLite's application_id).
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "db/database.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::RunDoasido;
using testing::TempDir;

std::int64_t Query(const std::filesystem::path& db, const std::string& sql) {
  sqlite3* raw = nullptr;
  EXPECT_EQ(sqlite3_open_v2(db.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(raw, sql.c_str(), -1, &st, nullptr);
  const std::int64_t v = sqlite3_step(st) == SQLITE_ROW ? sqlite3_column_int64(st, 0) : -1;
  sqlite3_finalize(st);
  sqlite3_close(raw);
  return v;
}

void Exec(const std::filesystem::path& db, const std::string& sql) {
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(raw);
}

TEST(DatabaseOpen, LookingCommandsRefuseAMissingFileAndCreateNothing) {
  TempDir dir;
  const auto typo = dir / "typo.db";
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"status", "--db", typo.string()},
        std::vector<std::string>{"queue", "list", "--db", typo.string()},
        std::vector<std::string>{"report", "--db", typo.string(), "--out",
                                 (dir / "report").string()}}) {
    const auto r = RunDoasido(args);
    EXPECT_EQ(r.exit_code, 2) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find("no doasido database"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(typo.string()), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(typo)) << args[0] << " created it";
  }
}

TEST(DatabaseOpen, AnotherProgramsSqliteFileIsRefusedUntouched) {
  TempDir dir;
  const auto foreign = dir / "photos.db";
  Exec(foreign, "CREATE TABLE albums (id INTEGER PRIMARY KEY, name TEXT);"
                "INSERT INTO albums (name) VALUES ('summer');");
  const auto tables = [&] { return Query(foreign, "SELECT COUNT(*) FROM sqlite_master"); };
  ASSERT_EQ(tables(), 1);
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"status", "--db", foreign.string()},
        std::vector<std::string>{"init", "--db", foreign.string()}}) {
    const auto r = RunDoasido(args);
    EXPECT_EQ(r.exit_code, 2) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find("not a doasido database"), std::string::npos) << r.err;
    EXPECT_EQ(tables(), 1) << args[0] << " added tables";
    EXPECT_EQ(Query(foreign, "PRAGMA application_id"), 0);
  }
  // A file that is not SQLite at all (a video named by mistake) is left as it was.
  const auto text = dir / "notes.db";
  { std::ofstream(text) << "these are not the tables you are looking for\n"; }
  const auto r = RunDoasido({"status", "--db", text.string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("not an SQLite file"), std::string::npos) << r.err;
  EXPECT_EQ(std::filesystem::file_size(text), 45u);
  // A file marked by some other application is refused too.
  const auto marked = dir / "other.db";
  Exec(marked, "PRAGMA application_id = 1234;");
  EXPECT_EQ(RunDoasido({"status", "--db", marked.string()}).exit_code, 2);
  EXPECT_EQ(Query(marked, "SELECT COUNT(*) FROM sqlite_master"), 0);
}

TEST(DatabaseOpen, OurFilesAreMarkedAndOlderOnesGetTheMark) {
  TempDir dir;
  const auto path = dir / "d.db";
  ASSERT_EQ(RunDoasido({"init", "--db", path.string()}).exit_code, 0);
  EXPECT_EQ(Query(path, "PRAGMA application_id"), Database::kApplicationId);
  // A database written before the mark existed: schema present, id 0.
  Exec(path, "PRAGMA application_id = 0;");
  const auto r = RunDoasido({"status", "--db", path.string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Query(path, "PRAGMA application_id"), Database::kApplicationId);
}

}  // namespace
}  // namespace doasido
