#include "dataset/parquet_writer.h"

#include <cstdio>
#include <fstream>

#include "core/error.h"
#include "dataset/duckdb_api.h"

namespace doasido::dataset {

namespace fs = std::filesystem;

// An in-memory DuckDB with one connection, single-threaded so that rows
// keep their order and chunks their boundaries.
class DuckDb {
 public:
  DuckDb() {
    if (duckdb_open(nullptr, &database) != DuckDBSuccess ||
        duckdb_connect(database, &connection) != DuckDBSuccess) {
      throw Error("parquet", "DuckDB cannot open an in-memory database");
    }
    Query("SET threads = 1", "");
    Query("SET preserve_insertion_order = true", "");
  }
  ~DuckDb() {
    if (connection) duckdb_disconnect(&connection);
    if (database) duckdb_close(&database);
  }
  // Runs `sql`; calls `row(text)` with the first column of each result row.
  template <typename F>
  void Query(const std::string& sql, const std::string& file, F row) {
    duckdb_result result;
    if (duckdb_query(connection, sql.c_str(), &result) != DuckDBSuccess) {
      const std::string message = duckdb_result_error(&result);
      duckdb_destroy_result(&result);
      throw Error("parquet", "DuckDB: " + message, {.file = file});
    }
    for (idx_t r = 0; r < duckdb_row_count(&result); ++r) {
      char* text = duckdb_value_varchar(&result, 0, r);
      row(std::string(text ? text : ""));
      duckdb_free(text);
    }
    duckdb_destroy_result(&result);
  }
  void Query(const std::string& sql, const std::string& file) {
    Query(sql, file, [](const std::string&) {});
  }

 private:
  duckdb_database database = nullptr;
  duckdb_connection connection = nullptr;
};

std::string SqlString(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    if (c == '\'') out += '\'';
    out += c;
  }
  return out + "'";
}

ParquetWriter::ParquetWriter(fs::path out, std::vector<ParquetColumn> columns, fs::path scratch_dir)
    : out_(std::move(out)), columns_(std::move(columns)), scratch_(std::move(scratch_dir)),
      db_(std::make_unique<DuckDb>()) {
  std::error_code ec;
  fs::create_directories(scratch_, ec);
  if (ec) throw Error("io", "cannot create: " + ec.message(), {.file = scratch_.string()});
}

ParquetWriter::~ParquetWriter() {
  std::error_code ec;
  for (const fs::path& p : parts_) fs::remove(p, ec);
}

void ParquetWriter::AddRowGroup(const std::vector<Json>& rows) {
  char name[32];
  std::snprintf(name, sizeof name, "part-%06zu.jsonl", parts_.size());
  const fs::path path = scratch_ / name;
  std::ofstream f(path, std::ios::binary);
  for (const Json& row : rows) f << row.dump(-1, ' ', false, Json::error_handler_t::replace) << '\n';
  f.close();
  if (!f) throw Error("io", "cannot stage Parquet rows", {.file = path.string()});
  parts_.push_back(path);
}

void ParquetWriter::SetMetadata(const std::string& key, const std::string& value) {
  metadata_.emplace_back(key, value);
}

void ParquetWriter::Finish() {
  std::string columns;
  for (const ParquetColumn& c : columns_) {
    columns += (columns.empty() ? "" : ", ") + SqlString(c.name) + ": " + SqlString(c.type);
  }
  std::string source;
  for (const fs::path& part : parts_) {
    source += (source.empty() ? "" : " UNION ALL ") + std::string("SELECT * FROM read_json(") +
              SqlString(part.string()) + ", format = 'newline_delimited', columns = {" + columns +
              "})";
  }
  if (source.empty()) {  // no rows: an empty file with the columns
    std::string nulls;
    for (const ParquetColumn& c : columns_) {
      nulls += (nulls.empty() ? "" : ", ") + std::string("NULL::") + c.type + " AS \"" + c.name + "\"";
    }
    source = "SELECT " + nulls + " LIMIT 0";
  }
  std::error_code ec;
  if (out_.has_parent_path()) fs::create_directories(out_.parent_path(), ec);
  std::string options = "FORMAT parquet, COMPRESSION snappy, ROW_GROUP_SIZE 1";
  if (!metadata_.empty()) {
    std::string kv;
    for (const auto& [key, value] : metadata_) {
      kv += (kv.empty() ? "" : ", ") + SqlString(key) + ": " + SqlString(value);
    }
    options += ", KV_METADATA {" + kv + "}";
  }
  db_->Query("COPY (" + source + ") TO " + SqlString(out_.string()) + " (" + options + ")",
             out_.string());
  for (const fs::path& p : parts_) fs::remove(p, ec);
  parts_.clear();
}

std::vector<std::string> DuckDbQuery(const std::string& sql) {
  DuckDb db;
  std::vector<std::string> out;
  db.Query(sql, "", [&out](const std::string& text) { out.push_back(text); });
  return out;
}

}  // namespace doasido::dataset
