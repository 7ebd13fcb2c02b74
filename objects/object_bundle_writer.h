// The objects stage's output: the object part of a clip bundle
// (recon/bundle/bundle.h, docs/clip_bundle.md), which recon's ReadBundle
// reads like any other, and objects.json:
//   meta.json          width, height, frames (the span's), fps, units "m",
//                      producers {"object_poses", "object_mesh", "K",
//                      recon::kObjectScaleProducer: kScaleFromHand |
//                      kScaleFromPrior, which tells recon the poses are metric}
//   K.npz              the hands stage's K
//   object/mesh.obj    the chosen track's cylinder or box (objects/object_shape.h)
//   object/poses.npz   (T,7) object -> camera, metres; frames before the
//                      track's first pose hold it, frames after its last
//                      (and between runs) hold the last one: objects.json
//                      says which frames were seen, filled or held
//   objects.json       LiftedObjectsJson below
// With no track (no known object) only objects.json is written.
#pragma once

#include <filesystem>

#include "core/config.h"
#include "objects/object_reconstruction.h"
#include "recon/bundle/bundle.h"

namespace doasido::objects {

// Per frame and object, the record `doasido objects` writes too:
//   {"first_frame" (file frame of frame 0), "K" [[3x3]], "chosen_track",
//    "tracks": [{"track", "category", "size_m" [x, y, z], "shape"
//       ("cylinder" | "box"), "scale_source", "scale_assumed",
//       "contact_frames", "contact_residual_m", "observed_frames",
//       "filled_frames" [...], "degenerate_frames" [...]}],
//    "unknown_categories": [...],
//    "frames": [{"frame": i, "objects": [{"category", "score", "track",
//       "keypoints_2d" [[u, v] x 9] (null when not observed),
//       "center_camera" [x, y, z], "rotation_camera" [[3x3]], "size_m",
//       "scale_assumed", "observed", "filled", "degenerate"}]}]}
// Every one of the span's `frame_count` frames has an entry (objects []
// where nothing was found); a frame lists each track posed or observed on it.
Json LiftedObjectsJson(const ObjectsResult& result, const Mat3& K, int first_frame, int frame_count);

// The bundle of the chosen track (requires result.chosen >= 0); `hands`
// gives the size, frame count, fps and K.
recon::ClipBundle ObjectBundle(const ObjectsResult& result, const recon::ClipBundle& hands,
                               int cylinder_segments = 48);

// Writes the files above into `dir` (created). Throws Error("io") naming the file.
void WriteObjectBundle(const ObjectsResult& result, const recon::ClipBundle& hands, int first_frame,
                       const std::filesystem::path& dir, int cylinder_segments = 48);

}  // namespace doasido::objects
