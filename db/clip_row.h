// Reading a clips row: the column list and its reader, shared by every query
// of the Database class that returns clips (internal to db/).
#pragma once

#include "core/records.h"
#include "db/statement.h"

namespace doasido::db {

// The columns ReadClipRow expects first, in order, for a `clips` table
// aliased as `c`.
inline constexpr const char* kClipColumns =
    "c.id, c.video_id, IFNULL(c.external_id, ''), c.start_frame, c.end_frame, c.start_s,"
    " c.end_s, IFNULL(c.source_list, ''), IFNULL(c.source_line, 0), c.metadata";

// The clip of the current row. Metadata that is not JSON (written by hand
// into the file) reads as an empty object rather than stopping the caller.
ClipRecord ReadClipRow(const Statement& q);

}  // namespace doasido::db
