#include "objects/objects_file.h"

#include "objects/box_keypoints_json.h"
#include "objects/object_bundle_writer.h"
#include "objects/object_reconstruction.h"

namespace doasido::objects {

Json ObjectsFileJson(const DetectedObjects& detected, const Mat3& K, const ObjectsConfig& config) {
  recon::ClipBundle camera;  // no hands: the span, its rate and the camera only
  camera.width = detected.width;
  camera.height = detected.height;
  camera.frames = static_cast<int>(detected.frames.size());
  camera.fps = detected.fps;
  camera.K = {K};
  std::vector<ObjectObservation> observations;
  for (std::size_t i = 0; i < detected.frames.size(); ++i) {
    for (ObjectObservation o : detected.frames[i]) {
      o.frame = static_cast<int>(i);
      observations.push_back(std::move(o));
    }
  }
  ObjectsConfig every_track = config;
  every_track.min_track_frames = 1;
  const ObjectsResult result = ReconstructObjects(observations, camera, every_track);
  Json out = LiftedObjectsJson(result, K, static_cast<int>(detected.first_frame), camera.frames);
  const Json plain = ObjectsJson(detected);
  for (const char* key : {"width", "height", "fps", "models"}) out[key] = plain.at(key);
  return out;
}

}  // namespace doasido::objects
