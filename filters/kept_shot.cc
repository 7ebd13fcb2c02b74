#include "filters/kept_shot.h"

#include "core/error.h"

namespace doasido::filters {
namespace {

// Keys of the shot-boundary stage's summary and of the "shot" block.
constexpr const char* kBoundaries = "boundaries";
constexpr const char* kTrim = "trim";
constexpr const char* kLongestSegment = "longest_segment";
constexpr const char* kStartFrame = "start_frame";
constexpr const char* kEndFrame = "end_frame";

FrameSpan SpanFromJson(const Json& j) {
  return {j.at(kStartFrame).get<std::int64_t>(), j.at(kEndFrame).get<std::int64_t>()};
}

std::vector<std::int64_t> BoundariesOf(const Json& object) {
  std::vector<std::int64_t> out;
  for (const Json& b : object.value(kBoundaries, Json::array())) out.push_back(b.get<std::int64_t>());
  return out;
}

}  // namespace

KeptShot KeptShotFromSummary(const Json& summary) {
  KeptShot shot;
  if (!summary.is_object()) return shot;
  try {
    shot.boundaries = BoundariesOf(summary);
    if (summary.contains(kTrim)) {
      shot.trim = SpanFromJson(summary.at(kTrim));
    } else if (!shot.boundaries.empty() && summary.contains(kLongestSegment)) {
      shot.trim = SpanFromJson(summary.at(kLongestSegment));  // rejected: judge its best shot
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error("bad_measurements", e.what(), {.field = "shot_boundary.summary"});
  }
  return shot;
}

std::optional<KeptShot> ReadKeptShot(const std::optional<Json>& measurements) {
  if (!measurements || !measurements->is_object() || !measurements->contains("summary")) {
    return std::nullopt;
  }
  return KeptShotFromSummary(measurements->at("summary"));
}

Json ToJson(const KeptShot& shot) {
  Json out = {{kBoundaries, shot.boundaries}};
  if (shot.trim) {
    out[kTrim] = {{kStartFrame, shot.trim->start_frame}, {kEndFrame, shot.trim->end_frame}};
  }
  return out;
}

KeptShot KeptShotFromJson(const Json& block) {
  KeptShot shot;
  try {
    shot.boundaries = BoundariesOf(block);
    if (block.contains(kTrim)) shot.trim = SpanFromJson(block.at(kTrim));
  } catch (const nlohmann::json::exception& e) {
    throw Error("bad_measurements", e.what(), {.field = "shot"});
  }
  return shot;
}

std::optional<KeptShot> ReadJudgedShot(const std::optional<Json>& measurements) {
  if (!measurements || !measurements->is_object() || !measurements->contains("shot")) {
    return std::nullopt;
  }
  return KeptShotFromJson(measurements->at("shot"));
}

}  // namespace doasido::filters
