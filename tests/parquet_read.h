// Reading a Parquet file back with an independent reader: hyparquet (npm,
// installed by scripts/setup.sh into core/data_dirs.h NpmDir()) through node.
#pragma once

#include <filesystem>

#include "core/config.h"
#include "core/data_dirs.h"
#include "tests/test_util.h"

namespace doasido::testing {

// Every row ({"rows": [...]}), the footer's key/value metadata ("kv") and
// the row-group sizes ("groups") of `file`; `dir` holds the node script.
inline Json ReadParquet(const std::filesystem::path& dir, const std::filesystem::path& file) {
  WriteFile(dir / "read.mjs", R"JS(
import { pathToFileURL } from 'node:url';
const hp = await import(pathToFileURL(process.argv[2] + '/node_modules/hyparquet/src/node.js'));
const file = await hp.asyncBufferFromFile(process.argv[3]);
const meta = await hp.parquetMetadataAsync(file);
const rows = await hp.parquetReadObjects({ file });
const big = (k, v) => typeof v === 'bigint' ? Number(v) : v;
const kv = Object.fromEntries((meta.key_value_metadata || []).map(e => [e.key, e.value]));
process.stdout.write(JSON.stringify({ rows, kv, groups: meta.row_groups.map(g => Number(g.num_rows)) }, big));
)JS");
  return Json::parse(ShellOk("node " + (dir / "read.mjs").string() + " " + NpmDir().string() + " " +
                             file.string()));
}

}  // namespace doasido::testing
