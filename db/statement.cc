#include "db/statement.h"

#include "core/error.h"
#include "core/error_codes.h"

namespace doasido::db {

namespace {

[[noreturn]] void ThrowReadOnly(sqlite3* db, const std::string& message) {
  const char* file = sqlite3_db_filename(db, "main");
  throw Error(kReadOnly,
              "cannot write: the database is read-only (a read-only filesystem or file; " +
                  message + ")",
              {.file = file ? file : ""});
}

}  // namespace

Statement::Statement(sqlite3* db, std::string_view sql) : db_(db) {
  if (sqlite3_prepare_v3(db, sql.data(), static_cast<int>(sql.size()), SQLITE_PREPARE_PERSISTENT,
                         &stmt_, nullptr) != SQLITE_OK) {
    throw Error("database", std::string(sqlite3_errmsg(db)) + " in: " + std::string(sql));
  }
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

void Statement::PrepareForBind() {
  if (stepped_) Reset();
}

Statement& Statement::Bind(int index, std::int64_t value) {
  PrepareForBind();
  sqlite3_bind_int64(stmt_, index, value);
  return *this;
}

Statement& Statement::Bind(int index, double value) {
  PrepareForBind();
  sqlite3_bind_double(stmt_, index, value);
  return *this;
}

Statement& Statement::Bind(int index, std::string_view value) {
  PrepareForBind();
  sqlite3_bind_text(stmt_, index, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT);
  return *this;
}

Statement& Statement::BindNull(int index) {
  PrepareForBind();
  sqlite3_bind_null(stmt_, index);
  return *this;
}

bool Statement::Step() {
  stepped_ = true;
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  const std::string message = sqlite3_errmsg(db_);
  const int code = rc;
  sqlite3_reset(stmt_);
  stepped_ = false;
  const char* file = sqlite3_db_filename(db_, "main");
  if ((code & 0xff) == SQLITE_READONLY) ThrowReadOnly(db_, message);
  throw Error(code == SQLITE_FULL ? "disk_full" : "database",
              code == SQLITE_FULL ? message
                                  : message + " (" + (sqlite3_sql(stmt_) ? sqlite3_sql(stmt_) : "") +
                                        ")",
              {.file = file ? file : ""});
}

void Statement::Run() {
  while (Step()) {
  }
  Reset();
}

void Statement::Reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
  stepped_ = false;
}

bool Statement::IsNull(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }
std::int64_t Statement::Int(int col) const { return sqlite3_column_int64(stmt_, col); }
double Statement::Real(int col) const { return sqlite3_column_double(stmt_, col); }
std::string Statement::Text(int col) const {
  const auto* text = sqlite3_column_text(stmt_, col);
  return text ? std::string(reinterpret_cast<const char*>(text),
                            static_cast<size_t>(sqlite3_column_bytes(stmt_, col)))
              : std::string();
}
std::optional<std::int64_t> Statement::OptInt(int col) const {
  return IsNull(col) ? std::nullopt : std::optional(Int(col));
}
std::optional<double> Statement::OptReal(int col) const {
  return IsNull(col) ? std::nullopt : std::optional(Real(col));
}

void Exec(sqlite3* db, const std::string& sql) {
  char* err = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string message = err ? err : "unknown";
    sqlite3_free(err);
    const char* file = sqlite3_db_filename(db, "main");
    if ((sqlite3_errcode(db) & 0xff) == SQLITE_READONLY) ThrowReadOnly(db, message);
    throw Error(message.find("full") != std::string::npos ? "disk_full" : "database", message,
                {.file = file ? file : ""});
  }
}

}  // namespace doasido::db
