// The shot the shot-boundary stage keeps of a clip: the typed reader of its
// stored measurements for every module that shows or judges that span
// (the later filters, the review page, the report, benches), so none of
// them rebuilds it from JSON keys and all of them agree.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "core/config.h"

namespace doasido::filters {

// Frames of the video file, both inclusive.
struct FrameSpan {
  std::int64_t start_frame = 0;
  std::int64_t end_frame = -1;
  bool operator==(const FrameSpan&) const = default;
};

struct KeptShot {
  // File frames that start a new shot, ascending.
  std::vector<std::int64_t> boundaries;
  // The span judged: the trim of a clip the stage passed trimmed, else (a
  // clip it rejected across a cut) its longest segment, so later filters
  // judge its best shot; none when the clip has no boundary.
  std::optional<FrameSpan> trim;
};

// From the shot-boundary stage's measurements "summary" (null or not an
// object: an empty KeptShot).
KeptShot KeptShotFromSummary(const Json& summary);
// From the stage's stored measurements; nullopt when there are none or they
// lack a summary (the stage has not decided this clip).
std::optional<KeptShot> ReadKeptShot(const std::optional<Json>& measurements);

// The "shot" block verdict stages store beside their signals:
// {"boundaries": [...], "trim": {"start_frame", "end_frame"}} (trim only
// when set), and its inverse (throws Error("bad_measurements")).
Json ToJson(const KeptShot& shot);
KeptShot KeptShotFromJson(const Json& block);
// The shot a verdict stage judged, from its stored measurements' "shot"
// block; nullopt when it has none (the shot stage had not run before it).
std::optional<KeptShot> ReadJudgedShot(const std::optional<Json>& measurements);

}  // namespace doasido::filters
