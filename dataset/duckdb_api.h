// The few functions of DuckDB's C API the project calls. libduckdb.so comes
// from the npm package @duckdb/node-bindings-linux-x64 (scripts/setup.sh)
// without its header, so the declarations are written here from DuckDB's
// documented C API (duckdb.h of v1.5).
#pragma once

#include <cstdint>

extern "C" {

typedef std::uint64_t idx_t;
typedef enum { DuckDBSuccess = 0, DuckDBError = 1 } duckdb_state;
typedef struct _duckdb_database {
  void* internal_ptr;
} * duckdb_database;
typedef struct _duckdb_connection {
  void* internal_ptr;
} * duckdb_connection;
// Layout as in duckdb.h: the fields are deprecated there and never read here.
typedef struct {
  idx_t deprecated_column_count;
  idx_t deprecated_row_count;
  idx_t deprecated_rows_changed;
  void* deprecated_columns;
  char* deprecated_error_message;
  void* internal_data;
} duckdb_result;

duckdb_state duckdb_open(const char* path, duckdb_database* out_database);
void duckdb_close(duckdb_database* database);
duckdb_state duckdb_connect(duckdb_database database, duckdb_connection* out_connection);
void duckdb_disconnect(duckdb_connection* connection);
duckdb_state duckdb_query(duckdb_connection connection, const char* query, duckdb_result* out_result);
void duckdb_destroy_result(duckdb_result* result);
const char* duckdb_result_error(duckdb_result* result);
idx_t duckdb_row_count(duckdb_result* result);
char* duckdb_value_varchar(duckdb_result* result, idx_t col, idx_t row);
void duckdb_free(void* ptr);

}  // extern "C"
