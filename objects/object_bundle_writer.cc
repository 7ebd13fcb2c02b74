#include "objects/object_bundle_writer.h"

#include <fstream>

#include "core/error.h"
#include "objects/object_shape.h"
#include "objects/objects_config.h"
#include "recon/align/reconstruct.h"

namespace doasido::objects {
namespace {

Json Vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

Json Matrix(const Mat3& m) {
  Json rows = Json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2)});
  return rows;
}

Json FrameList(const ObjectTrack& t, bool ObjectFrame::*flag) {
  Json list = Json::array();
  for (int k = 0; k < static_cast<int>(t.frames.size()); ++k) {
    if (t.frames[k].*flag) list.push_back(k);
  }
  return list;
}

Json TrackSummary(const ObjectTrack& t) {
  return {{"track", t.track},
          {"category", t.category},
          {"size_m", Vec(t.size_m)},
          {"shape", t.symmetric ? "cylinder" : "box"},
          {"scale_source", t.scale_source},
          {"scale_assumed", t.scale_assumed},
          {"contact_frames", t.contact_frames},
          {"contact_residual_m", t.contact_residual_m},
          {"observed_frames", t.ObservedFrames()},
          {"filled_frames", FrameList(t, &ObjectFrame::filled)},
          {"degenerate_frames", FrameList(t, &ObjectFrame::degenerate)}};
}

Json FrameObject(const ObjectTrack& t, const ObjectFrame& f) {
  Json keypoints = nullptr;
  if (f.observed) {
    keypoints = Json::array();
    for (const Vec2& p : f.keypoints) keypoints.push_back({p.x(), p.y()});
  }
  Json o = {{"category", t.category}, {"score", f.score},         {"track", t.track},
            {"keypoints_2d", keypoints},  {"size_m", Vec(t.size_m)}, {"scale_assumed", t.scale_assumed},
            {"observed", f.observed},     {"filled", f.filled},       {"degenerate", f.degenerate}};
  o["center_camera"] = f.posed ? Vec(f.pose.t) : Json(nullptr);
  o["rotation_camera"] = f.posed ? Matrix(f.pose.R()) : Json(nullptr);
  return o;
}

// The chosen track's pose of every frame: its own where posed, else the
// nearest earlier one, else the first (see the header).
std::vector<Pose> HeldPoses(const ObjectTrack& t) {
  const int T = static_cast<int>(t.frames.size());
  std::vector<Pose> out(T);
  int first = -1;
  for (int k = 0; k < T && first < 0; ++k) {
    if (t.frames[k].posed) first = k;
  }
  Pose held = t.frames[first].pose;
  for (int k = 0; k < T; ++k) {
    if (t.frames[k].posed) held = t.frames[k].pose;
    out[k] = held;
  }
  return out;
}

void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw Error("io", "cannot write", {.file = path.string()});
}

}  // namespace

Json LiftedObjectsJson(const ObjectsResult& result, const Mat3& K, int first_frame, int frame_count) {
  Json tracks = Json::array();
  for (const ObjectTrack& t : result.tracks) tracks.push_back(TrackSummary(t));
  Json frames = Json::array();
  for (int k = 0; k < frame_count; ++k) {
    Json objects = Json::array();
    for (const ObjectTrack& t : result.tracks) {
      if (k >= static_cast<int>(t.frames.size())) continue;
      const ObjectFrame& f = t.frames[k];
      if (f.posed || f.observed) objects.push_back(FrameObject(t, f));
    }
    frames.push_back({{"frame", k}, {"objects", objects}});
  }
  return {{"first_frame", first_frame},
          {"K", Matrix(K)},
          {"chosen_track", result.chosen >= 0 ? Json(result.tracks[result.chosen].track) : Json(nullptr)},
          {"tracks", tracks},
          {"unknown_categories", result.unknown_categories},
          {"frames", frames}};
}

recon::ClipBundle ObjectBundle(const ObjectsResult& result, const recon::ClipBundle& hands,
                               int cylinder_segments) {
  const ObjectTrack& t = result.tracks.at(result.chosen);
  recon::ClipBundle b;
  b.width = hands.width;
  b.height = hands.height;
  b.frames = hands.frames;
  b.fps = hands.fps;
  b.K = hands.K;
  b.producers = {
      {"object_poses", "MediaPipe Objectron box landmarks (" + t.category +
                           "), doasido EPnP lifting and one Ceres smoothing per track"},
      {"object_mesh", std::string(t.symmetric ? "cylinder" : "box") + " of the lifted box's extents"},
      {"K", hands.producers.value("K", std::string("hands"))},
      {recon::kObjectScaleProducer, t.scale_source}};
  b.object_mesh = ObjectMesh(t.size_m, t.symmetric, cylinder_segments);
  b.object_poses = HeldPoses(t);
  return b;
}

void WriteObjectBundle(const ObjectsResult& result, const recon::ClipBundle& hands, int first_frame,
                       const std::filesystem::path& dir, int cylinder_segments) {
  std::filesystem::create_directories(dir);
  if (result.chosen >= 0) recon::WriteBundle(ObjectBundle(result, hands, cylinder_segments), dir);
  const Mat3 K = hands.K.empty() ? Mat3::Identity() : hands.KAt(0);
  WriteText(dir / kObjectsFile, LiftedObjectsJson(result, K, first_frame, hands.frames).dump() + "\n");
}

}  // namespace doasido::objects
