// Database: ingest (videos, clips, detections, events) and reading them back.
#include "db/database.h"

#include "core/bounded_text.h"

#include <sqlite3.h>

#include "db/clip_row.h"
#include "db/statement.h"

namespace doasido {

// ---- Ingest -----------------------------------------------------------------

VideoId Database::UpsertVideo(const std::string& path_or_url) {
  const std::string stored = Store(path_or_url);
  auto& find = Prepare("SELECT id FROM videos WHERE path = ?");
  find.Bind(1, stored);
  if (find.Step()) {
    const VideoId id = find.Int(0);
    find.Reset();
    return id;
  }
  find.Reset();
  Prepare("INSERT INTO videos (path) VALUES (?)").Bind(1, stored).Run();
  return sqlite3_last_insert_rowid(db_);
}

Database::InsertResult Database::InsertClip(const ClipRecord& clip) {
  if (pipeline_cache_.empty()) Pipeline();
  if (pipeline_cache_.empty()) {
    throw Error("pipeline", "the database has no pipeline: run `doasido init` first",
                {.file = path_.string()});
  }
  auto& insert = Prepare(
      "INSERT OR IGNORE INTO clips (video_id, external_id, start_frame, end_frame, start_s, end_s,"
      " source_list, source_line, metadata, created_at) VALUES (?,?,?,?,?,?,?,?,?,?)");
  insert.Bind(1, clip.video_id)
      .Bind(2, clip.external_id)
      .Bind(3, clip.start_frame)
      .Bind(4, clip.end_frame)
      .Bind(5, clip.start_s)
      .Bind(6, clip.end_s)
      .Bind(7, clip.source_list)
      .Bind(8, static_cast<std::int64_t>(clip.source_line))
      .Bind(9, clip.metadata.dump())
      .Bind(10, Now())
      .Run();
  if (sqlite3_changes(db_) == 0) {
    auto& find = Prepare(
        "SELECT id FROM clips WHERE video_id = ? AND IFNULL(start_frame, -1) = IFNULL(?, -1) AND "
        "IFNULL(end_frame, -1) = IFNULL(?, -1) AND IFNULL(start_s, -1) = IFNULL(?, -1) AND "
        "IFNULL(end_s, -1) = IFNULL(?, -1)");
    find.Bind(1, clip.video_id)
        .Bind(2, clip.start_frame)
        .Bind(3, clip.end_frame)
        .Bind(4, clip.start_s)
        .Bind(5, clip.end_s);
    const ClipId id = find.Step() ? find.Int(0) : 0;
    find.Reset();
    return {id, false};
  }
  const ClipId id = sqlite3_last_insert_rowid(db_);
  Prepare("INSERT INTO stage_runs (clip_id, stage, position, state) VALUES (?, ?, 0, 'pending')")
      .Bind(1, id)
      .Bind(2, pipeline_cache_.front())
      .Run();
  return {id, true};
}

void Database::AddDetections(ClipId clip, const std::vector<Detection>& detections) {
  auto& insert = Prepare(
      "INSERT INTO detections (clip_id, frame, kind, x1, y1, x2, y2, score, contact_state,"
      " hand_side, dx, dy, magnitude, source) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
  for (const auto& d : detections) {
    insert.Bind(1, clip)
        .Bind(2, d.frame)
        .Bind(3, d.kind)
        .Bind(4, d.x1)
        .Bind(5, d.y1)
        .Bind(6, d.x2)
        .Bind(7, d.y2)
        .Bind(8, d.score)
        .Bind(9, d.contact_state)
        .Bind(10, d.hand_side)
        .Bind(11, d.dx)
        .Bind(12, d.dy)
        .Bind(13, d.magnitude)
        .Bind(14, d.source)
        .Run();
  }
}

void Database::LogEvent(std::optional<ClipId> clip, const std::string& stage,
                        const std::string& kind, const std::string& worker,
                        const std::string& detail) {
  Prepare("INSERT INTO events (at, clip_id, stage, kind, worker, detail) VALUES (?,?,?,?,?,?)")
      .Bind(1, Now())
      .Bind(2, clip)
      .Bind(3, stage)
      .Bind(4, kind)
      .Bind(5, worker)
      .Bind(6, BoundedTail(detail))
      .Run();
}

// ---- Reading ----------------------------------------------------------------

ClipRecord Database::GetClip(ClipId id) {
  auto& q = Prepare(std::string("SELECT ") + db::kClipColumns + " FROM clips c WHERE c.id = ?");
  q.Bind(1, id);
  if (!q.Step()) {
    q.Reset();
    throw Error("no_such_clip", "no clip with this id", {.clip = std::to_string(id)});
  }
  ClipRecord c = db::ReadClipRow(q);
  q.Reset();
  return c;
}

VideoRecord Database::GetVideo(VideoId id) {
  auto& q = Prepare(
      "SELECT id, COALESCE(local_path, path), width, height, fps, frame_count, duration_s,"
      " variable_frame_rate, rotation_deg, codec, probed_at FROM videos WHERE id = ?");
  q.Bind(1, id);
  if (!q.Step()) {
    q.Reset();
    throw Error("no_such_video", "no video with id " + std::to_string(id));
  }
  VideoRecord v;
  v.id = q.Int(0);
  v.path = Resolve(q.Text(1)).string();
  if (!q.IsNull(10)) {
    VideoInfo info;
    info.width = static_cast<int>(q.Int(2));
    info.height = static_cast<int>(q.Int(3));
    info.fps = q.Real(4);
    info.frame_count = q.Int(5);
    info.duration_s = q.Real(6);
    info.variable_frame_rate = q.Int(7) != 0;
    info.rotation_deg = static_cast<int>(q.Int(8));
    info.codec = q.Text(9);
    v.info = info;
  }
  q.Reset();
  return v;
}

std::vector<Detection> Database::GetDetections(ClipId clip) {
  auto& q = Prepare(
      "SELECT frame, kind, x1, y1, x2, y2, score, contact_state, hand_side, dx, dy, magnitude,"
      " source FROM detections WHERE clip_id = ? ORDER BY frame, id");
  q.Bind(1, clip);
  std::vector<Detection> out;
  while (q.Step()) {
    Detection d;
    d.frame = q.Int(0);
    d.kind = q.Text(1);
    d.x1 = q.Real(2);
    d.y1 = q.Real(3);
    d.x2 = q.Real(4);
    d.y2 = q.Real(5);
    d.score = q.Real(6);
    d.contact_state = static_cast<int>(q.Int(7));
    d.hand_side = static_cast<int>(q.Int(8));
    d.dx = q.Real(9);
    d.dy = q.Real(10);
    d.magnitude = q.Real(11);
    d.source = q.Text(12);
    out.push_back(std::move(d));
  }
  q.Reset();
  return out;
}

std::optional<Json> Database::GetMeasurements(ClipId clip, const std::string& stage) {
  auto& q = Prepare("SELECT data FROM measurements WHERE clip_id = ? AND stage = ?");
  q.Bind(1, clip).Bind(2, stage);
  std::optional<Json> out;
  if (q.Step()) out = Json::parse(q.Text(0));
  q.Reset();
  return out;
}

ClipContext Database::LoadContext(ClipId clip, const std::string& stage) {
  ClipContext ctx;
  ctx.clip = GetClip(clip);
  ctx.video = GetVideo(ctx.clip.video_id);
  ctx.detections = GetDetections(clip);
  const int position = StagePosition(stage);
  auto& q = Prepare(
      "SELECT m.stage, m.data FROM measurements m JOIN pipeline p ON p.stage = m.stage"
      " WHERE m.clip_id = ? AND p.position < ?");
  q.Bind(1, clip).Bind(2, position);
  while (q.Step()) ctx.measurements[q.Text(0)] = Json::parse(q.Text(1));
  q.Reset();
  ctx.artifact_dir = ArtifactDir(clip, stage);
  for (const std::string& earlier : Pipeline()) {
    if (earlier == stage) break;
    if (auto out = RecordedOutput(clip, earlier, true)) ctx.inputs[earlier] = out->dir;
  }
  return ctx;
}

std::int64_t Database::QueryInt(const std::string& sql) {
  auto& q = Prepare(sql);
  const std::int64_t n = q.Step() ? q.Int(0) : 0;
  q.Reset();
  return n;
}

std::int64_t Database::CountClips() { return QueryInt("SELECT COUNT(*) FROM clips"); }

std::int64_t Database::CountVideos() { return QueryInt("SELECT COUNT(*) FROM videos"); }

}  // namespace doasido
