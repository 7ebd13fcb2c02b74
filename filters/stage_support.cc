#include "filters/stage_support.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace doasido::filters {

Json CopyAnalysis(const ClipContext& context, const std::string& section) {
  const ErrorSite site{.clip = context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                                                : context.clip.external_id,
                       .file = context.video.path,
                       .field = std::string(kAnalyzeStageName) + "." + section};
  auto it = context.measurements.find(kAnalyzeStageName);
  if (it == context.measurements.end()) {
    throw Error("missing_measurements",
                std::string("stage ") + kAnalyzeStageName + " has not run on this clip", site);
  }
  const Json& analysis = it->second;
  if (!analysis.is_object() || !analysis.contains("clip") || !analysis.contains(section)) {
    throw Error("missing_measurements", "the analysis measurements lack this section", site);
  }
  Json out{{"clip", analysis.at("clip")}, {"signals", analysis.at(section)}};
  auto shot = context.measurements.find("shot_boundary");
  if (shot != context.measurements.end() && shot->second.contains("summary")) {
    const Json& summary = shot->second.at("summary");
    out["shot"] = {{"boundaries", summary.value("boundaries", Json::array())}};
    if (summary.contains("trim")) {
      out["shot"]["trim"] = summary.at("trim");
    } else if (!out["shot"]["boundaries"].empty() && summary.contains("longest_segment")) {
      out["shot"]["trim"] = summary.at("longest_segment");  // rejected: judge its best shot
    }
  }
  return out;
}

ShotSpan SpanOf(const Json& measurements, std::int64_t frames) {
  ShotSpan span;
  span.last = frames - 1;
  if (!measurements.contains("shot")) return span;
  const auto first = static_cast<std::int64_t>(NumberOr(measurements.at("clip"), "first_frame", 0));
  const Json& shot = measurements.at("shot");
  if (shot.contains("trim")) {
    span.first =
        std::max<std::int64_t>(0, shot.at("trim").at("start_frame").get<std::int64_t>() - first);
    span.last = std::min(frames - 1, shot.at("trim").at("end_frame").get<std::int64_t>() - first);
  }
  for (const Json& b : shot.value("boundaries", Json::array())) {
    span.boundaries.push_back(b.get<std::int64_t>() - first);
  }
  return span;
}

void RequireAnalysis(const Json& measurements, const std::string& stage) {
  if (!measurements.is_object() || !measurements.contains("clip") ||
      !measurements.contains("signals") || !measurements.at("clip").is_object() ||
      !measurements.at("signals").is_object()) {
    throw Error("bad_measurements", "stored measurements lack \"clip\" or \"signals\"",
                {.field = stage});
  }
}

Json ScoreEntry(const std::string& name, double value, bool rejects_above, double reject,
                double flag) {
  Json entry = {{"name", name},
                {"value", value},
                {"rejects", rejects_above ? "above" : "below"},
                {"reject", reject}};
  if (!std::isnan(flag)) entry["flag"] = flag;
  return entry;
}

double NumberOr(const Json& object, const std::string& key, double fallback) {
  if (!object.is_object()) return fallback;
  auto it = object.find(key);
  if (it == object.end() || !it->is_number()) return fallback;
  return it->get<double>();
}

}  // namespace doasido::filters
