#include "objects/object_detection.h"

#include "core/error.h"
#include "core/file_text.h"
#include "objects/box_tracker.h"
#include "objects/objects_in_video.h"

namespace doasido::objects {
namespace {

constexpr const char* kBadObservations = "bad_observations";

ObjectObservation ReadObject(const Json& o, int frame, const std::string& file,
                             const std::string& where) {
  auto fail = [&](const std::string& field, const std::string& what) -> Error {
    return Error(kBadObservations, where + ": " + what, {.file = file, .field = field});
  };
  if (!o.is_object()) throw fail("objects", "not an object");
  ObjectObservation out;
  out.frame = frame;
  if (!o.contains("category") || !o["category"].is_string()) throw fail("category", "missing or not a string");
  out.category = o["category"].get<std::string>();
  if (!o.contains("score") || !o["score"].is_number()) throw fail("score", "missing or not a number");
  out.score = o["score"].get<float>();
  if (!o.contains("track") || !o["track"].is_number_integer()) throw fail("track", "missing or not an integer");
  out.track = o["track"].get<int>();
  const Json& k = o.contains("keypoints_2d") ? o["keypoints_2d"] : Json();
  if (!k.is_array() || k.size() != kBoxKeypoints) throw fail("keypoints_2d", "must be 9 [x, y] pairs");
  for (int i = 0; i < kBoxKeypoints; ++i) {
    if (!k[i].is_array() || k[i].size() != 2 || !k[i][0].is_number() || !k[i][1].is_number()) {
      throw fail("keypoints_2d", "keypoint " + std::to_string(i) + " is not [x, y]");
    }
    out.keypoints_2d[i] = {k[i][0].get<double>(), k[i][1].get<double>()};
  }
  return out;
}

}  // namespace

std::vector<ObjectObservation> ObservationsFromJson(const Json& json, const FrameSpan& span,
                                                    const std::string& file) {
  if (!json.is_object() || !json.contains("frames") || !json["frames"].is_array()) {
    throw Error(kBadObservations, "no \"frames\" array", {.file = file, .field = "frames"});
  }
  const int first = json.value("first_frame", 0);
  std::vector<ObjectObservation> out;
  for (const Json& f : json["frames"]) {
    if (!f.is_object() || !f.contains("frame") || !f["frame"].is_number_integer()) {
      throw Error(kBadObservations, "a frame without an integer \"frame\"", {.file = file, .field = "frame"});
    }
    const int frame = first + f["frame"].get<int>() - span.first_frame;
    if (frame < 0 || frame >= span.frames) continue;
    if (!f.contains("objects")) continue;
    if (!f["objects"].is_array()) {
      throw Error(kBadObservations, "\"objects\" is not an array", {.file = file, .field = "objects"});
    }
    for (const Json& o : f["objects"]) {
      if (o.is_object() && o.contains("keypoints_2d") && o["keypoints_2d"].is_null()) continue;  // not seen
      out.push_back(ReadObject(o, frame, file, "frame " + std::to_string(f["frame"].get<int>())));
    }
  }
  return out;
}

namespace {

// The category models on every frame of the span; frames counted from its start.
std::vector<ObjectObservation> RunModels(const std::filesystem::path& video, const FrameSpan& span,
                                         const BoxKeypointsConfig& config, const HandsByFrame* hands,
                                         const std::vector<SeedBox>& seeds) {
  BoxTracker tracker(config, video.stem().string());
  DecoderOptions options{.clip = video.stem().string()};
  options.first_frame = span.first_frame;
  options.last_frame = span.first_frame + span.frames - 1;
  const DetectedObjects detected = ObjectsInVideo(video, options, config.max_side, tracker, {}, seeds, hands);
  std::vector<ObjectObservation> out;
  for (const auto& frame : detected.frames) {
    for (ObjectObservation o : frame) {
      o.frame -= span.first_frame;
      if (o.frame >= 0 && o.frame < span.frames) out.push_back(std::move(o));
    }
  }
  return out;
}

}  // namespace

std::vector<ObjectObservation> DetectObjects(const std::filesystem::path& video, const FrameSpan& span,
                                             const ObjectsConfig& config, const HandsByFrame* hands,
                                             const std::vector<SeedBox>& seeds) {
  if (config.observations_dir.empty()) return RunModels(video, span, config.models, hands, seeds);
  const auto file = std::filesystem::path(config.observations_dir) / (video.stem().string() + ".json");
  if (!std::filesystem::is_regular_file(file)) {
    throw Error(kErrorObservationsMissing, "no observations for video " + video.string(),
                {.file = file.string(), .field = "objects.observations_dir"});
  }
  Json json;
  try {
    json = Json::parse(ReadFileOrThrow(file, "io", "cannot read"));
  } catch (const Json::exception& e) {
    throw Error(kBadObservations, e.what(), {.file = file.string()});
  }
  return ObservationsFromJson(json, span, file.string());
}

HandsByFrame HandsFromBundle(const recon::ClipBundle& hands, int first_frame) {
  HandsByFrame out;
  if (hands.K.empty()) return out;
  for (const auto* side : {&hands.hand_left, &hands.hand_right}) {
    if (!side->has_value()) continue;
    const recon::HandTrack& h = **side;
    for (size_t t = 0; t < h.valid.size() && t < h.joints.size(); ++t) {
      if (!h.valid[t]) continue;
      const Mat3& K = hands.KAt(static_cast<int>(t));
      HandPoints2d p;
      bool ok = true;
      for (int k = 0; k < kHandPoints && ok; ++k) {
        const Vec3 uv = K * h.joints[t].row(k).transpose();
        ok = uv.allFinite() && uv.z() > 0;
        if (ok) p[k] = uv.head<2>() / uv.z() + Vec2(0.5, 0.5);  // K's pixel centres are integers
      }
      if (ok) out[first_frame + static_cast<std::int64_t>(t)].push_back(p);
    }
  }
  return out;
}

}  // namespace doasido::objects
