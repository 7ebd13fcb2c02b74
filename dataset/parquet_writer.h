// Parquet files written through DuckDB (an in-memory database, one thread):
// rows are handed over as JSON objects, one group of rows per row group.
//
// Row groups: DuckDB's writer flushes a row group at the end of every chunk
// it receives when ROW_GROUP_SIZE is 1, and a scan of one group's rows
// yields its own chunks of at most 2,048 rows (DuckDB's vector size). So a
// group of up to 2,048 rows is exactly one row group (LeRobot writes one per
// episode: 68 s at 30 fps); a longer group is split at every 2,048 rows.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/config.h"

namespace doasido::dataset {

struct ParquetColumn {
  std::string name;  // any text: quoted in SQL
  std::string type;  // a DuckDB type: BIGINT, FLOAT, DOUBLE, VARCHAR, FLOAT[7], VARCHAR[], ...
};

class ParquetWriter {
 public:
  // Rows are staged as JSON lines in `scratch_dir` (created; emptied by
  // Finish). Throws Error("parquet") when DuckDB cannot start.
  ParquetWriter(std::filesystem::path out, std::vector<ParquetColumn> columns,
                std::filesystem::path scratch_dir);
  ~ParquetWriter();
  ParquetWriter(const ParquetWriter&) = delete;
  ParquetWriter& operator=(const ParquetWriter&) = delete;

  // Adds one row group; each row is an object with a member per column
  // (null or missing: NULL). Throws Error("io") naming the staging file.
  void AddRowGroup(const std::vector<Json>& rows);
  // Key/value metadata of the file footer (e.g. pandas' "pandas" schema).
  void SetMetadata(const std::string& key, const std::string& value);
  // Writes the file (snappy). Throws Error("parquet") with DuckDB's message,
  // naming the output file.
  void Finish();

 private:
  std::filesystem::path out_;
  std::vector<ParquetColumn> columns_;
  std::filesystem::path scratch_;
  std::vector<std::filesystem::path> parts_;
  std::vector<std::pair<std::string, std::string>> metadata_;
  std::unique_ptr<class DuckDb> db_;
};

// Runs one DuckDB query on an in-memory database and returns the first
// column of every row as text (NULL as ""), e.g. to read a file back.
// Throws Error("parquet") with DuckDB's message.
std::vector<std::string> DuckDbQuery(const std::string& sql);

// `text` as a SQL string literal.
std::string SqlString(const std::string& text);

}  // namespace doasido::dataset
