// The objects' 2D box keypoints as JSON, the format `doasido objects`
// writes (<out>/<stem>.json):
//   {"width", "height", "fps", "first_frame",
//    "models": {"detector_runs", "detector_ms", "landmark_runs", "landmark_ms"},
//    "frames": [{"frame": i, "objects": [{"category", "score", "track",
//                                          "keypoints_2d": [[x, y] x 9]}]}]}
// keypoint 0 the box centre, 1-8 the corners (objects/box_keypoints.h),
// pixels of the input as displayed. `doasido objects` writes these beside
// the lifted 3D fields (objects/objects_file.h).
#pragma once

#include "core/config.h"
#include "objects/objects_in_video.h"

namespace doasido::objects {

// Object keys, one name each.
inline constexpr const char* kCategoryKey = "category";
inline constexpr const char* kScoreKey = "score";
inline constexpr const char* kTrackKey = "track";
inline constexpr const char* kKeypoints2dKey = "keypoints_2d";

Json ObservationJson(const ObjectObservation& o);
Json ObjectsJson(const DetectedObjects& detected);

// Back from JSON; throws Error("bad_json") naming the key.
ObjectObservation ObservationFromJson(const Json& j, int frame);

}  // namespace doasido::objects
