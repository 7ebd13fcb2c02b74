#include "db/clip_row.h"

namespace doasido::db {

ClipRecord ReadClipRow(const Statement& q) {
  ClipRecord c;
  c.id = q.Int(0);
  c.video_id = q.Int(1);
  c.external_id = q.Text(2);
  c.start_frame = q.OptInt(3);
  c.end_frame = q.OptInt(4);
  c.start_s = q.OptReal(5);
  c.end_s = q.OptReal(6);
  c.source_list = q.Text(7);
  c.source_line = static_cast<long>(q.Int(8));
  c.metadata = Json::parse(q.Text(9), nullptr, false);
  if (c.metadata.is_discarded()) c.metadata = Json::object();
  return c;
}

}  // namespace doasido::db
