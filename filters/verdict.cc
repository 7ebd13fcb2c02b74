#include "filters/verdict.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "filters/kept_shot.h"
#include "filters/shot_boundary.h"

namespace doasido::filters {

Json VerdictInput(const Json& analysis, const std::string& section, const Json* shot_verdict,
                  const ErrorSite& site) {
  if (analysis.is_object() && analysis.contains("clip") && !analysis.contains(section) &&
      analysis.contains(kNotMeasuredKey)) {
    const Json& marker = analysis.at(kNotMeasuredKey);
    const Json sections = marker.value("sections", Json::array());
    if (std::find(sections.begin(), sections.end(), section) != sections.end()) {
      return {{"clip", analysis.at("clip")}, {kNotMeasuredKey, marker}};
    }
  }
  if (!analysis.is_object() || !analysis.contains("clip") || !analysis.contains(section)) {
    throw Error("missing_measurements", "the analysis measurements lack this section", site);
  }
  Json out{{"clip", analysis.at("clip")}, {"signals", analysis.at(section)}};
  if (shot_verdict != nullptr) {
    if (const auto kept = ReadKeptShot(*shot_verdict)) out["shot"] = ToJson(*kept);
  }
  return out;
}

std::optional<FilterVerdict> NotMeasured(const Json& input) {
  if (!input.is_object() || !input.contains(kNotMeasuredKey)) return std::nullopt;
  const Json& marker = input.at(kNotMeasuredKey);
  if (!marker.is_object() || !marker.contains("stage") || !marker.at("stage").is_string()) {
    throw Error("bad_measurements", "\"not_measured\" lacks the stage that decided the clip",
                {.field = kNotMeasuredKey});
  }
  FilterVerdict out;
  out.verdict = Verdict::kNotMeasured;
  out.reason = marker.at("stage").get<std::string>();
  out.measurements = input;
  return out;
}

ShotSpan SpanOf(const Json& measurements, std::int64_t frames) {
  ShotSpan span;
  span.last = frames - 1;
  if (!measurements.contains("shot")) return span;
  const auto first = static_cast<std::int64_t>(NumberOr(measurements.at("clip"), "first_frame", 0));
  const KeptShot shot = KeptShotFromJson(measurements.at("shot"));
  if (shot.trim) {
    span.first = std::max<std::int64_t>(0, shot.trim->start_frame - first);
    span.last = std::min(frames - 1, shot.trim->end_frame - first);
  }
  for (std::int64_t b : shot.boundaries) span.boundaries.push_back(b - first);
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

std::vector<int> IntArray(const Json& j, const char* key) {
  if (!j.contains(key) || !j.at(key).is_array()) {
    throw Error("bad_measurements", "missing per-frame array", {.field = key});
  }
  return j.at(key).get<std::vector<int>>();
}

double NumberOr(const Json& object, const std::string& key, double fallback) {
  if (!object.is_object()) return fallback;
  auto it = object.find(key);
  if (it == object.end() || !it->is_number()) return fallback;
  return it->get<double>();
}

}  // namespace doasido::filters
