#include "objects/box_keypoints_json.h"

#include "core/error.h"

namespace doasido::objects {

Json ObservationJson(const ObjectObservation& o) {
  Json points = Json::array();
  for (const Eigen::Vector2d& p : o.keypoints_2d) points.push_back({p.x(), p.y()});
  return {{kCategoryKey, o.category}, {kScoreKey, o.score}, {kTrackKey, o.track},
          {kKeypoints2dKey, points}};
}

Json ObjectsJson(const DetectedObjects& d) {
  Json frames = Json::array();
  for (std::size_t i = 0; i < d.frames.size(); ++i) {
    Json objects = Json::array();
    for (const ObjectObservation& o : d.frames[i]) objects.push_back(ObservationJson(o));
    frames.push_back({{"frame", d.first_frame + static_cast<std::int64_t>(i)}, {"objects", objects}});
  }
  return {{"width", d.width},
          {"height", d.height},
          {"fps", d.fps},
          {"first_frame", d.first_frame},
          {"models",
           {{"detector_runs", d.detector_runs},
            {"detector_ms", d.detector_ms},
            {"landmark_runs", d.landmark_runs},
            {"landmark_ms", d.landmark_ms}}},
          {"frames", frames}};
}

ObjectObservation ObservationFromJson(const Json& j, int frame) {
  ObjectObservation o{.frame = frame};
  try {
    o.category = j.at(kCategoryKey).get<std::string>();
    o.score = j.at(kScoreKey).get<float>();
    o.track = j.at(kTrackKey).get<int>();
    const Json& points = j.at(kKeypoints2dKey);
    if (points.size() != kBoxKeypoints) {
      throw Error("bad_json", "keypoints_2d must hold 9 points", {.field = kKeypoints2dKey});
    }
    for (int k = 0; k < kBoxKeypoints; ++k) {
      o.keypoints_2d[k] = {points.at(k).at(0).get<double>(), points.at(k).at(1).get<double>()};
    }
  } catch (const Json::exception& e) {
    throw Error("bad_json", std::string("an object entry: ") + e.what());
  }
  return o;
}

}  // namespace doasido::objects
