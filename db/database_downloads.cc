// Videos named by URL and their downloaded files (schema v4).
#include "core/error.h"
#include "db/database.h"
#include "db/statement.h"

namespace doasido {

void Database::RecordVideoFile(ClipId clip, const Json& file) {
  const ErrorSite site{.clip = std::to_string(clip), .field = kVideoFileKey};
  if (!file.is_object() || !file.contains("path") || !file.contains("size_bytes") ||
      !file.contains("sha256") || !file.at("path").is_string() ||
      !file.at("size_bytes").is_number_integer() || !file.at("sha256").is_string()) {
    throw Error("bad_measurements", "needs path (text), size_bytes (integer) and sha256 (text)",
                site);
  }
  Prepare("UPDATE videos SET local_path = ?, size_bytes = ?, sha256 = ?, downloaded_at = ?"
          " WHERE id = (SELECT video_id FROM clips WHERE id = ?)")
      .Bind(1, Store(file.at("path").get<std::string>()))
      .Bind(2, file.at("size_bytes").get<std::int64_t>())
      .Bind(3, file.at("sha256").get<std::string>())
      .Bind(4, Now())
      .Bind(5, clip)
      .Run();
}

std::optional<Database::VideoFile> Database::GetVideoFile(VideoId video) {
  auto& q = Prepare("SELECT path, local_path, size_bytes, sha256, downloaded_at FROM videos"
                    " WHERE id = ? AND local_path IS NOT NULL");
  q.Bind(1, video);
  std::optional<VideoFile> out;
  if (q.Step()) {
    out = VideoFile{.url = q.Text(0),
                    .local_path = Resolve(q.Text(1)).string(),
                    .size_bytes = q.Int(2),
                    .sha256 = q.Text(3),
                    .downloaded_at = q.Real(4)};
  }
  q.Reset();
  return out;
}

std::int64_t Database::CountDownloadedVideos() {
  return QueryInt("SELECT COUNT(*) FROM videos WHERE local_path IS NOT NULL");
}

}  // namespace doasido
