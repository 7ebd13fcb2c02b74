// Where the objects stage gets its box keypoints: by default the category
// models run in process on the clip's span (objects/objects_in_video.h,
// [objects.models]); with [objects] observations_dir set, the stage reads
// what `doasido objects` (or any tool) wrote there instead:
// the file <observations_dir>/<video stem>.json, in
// the objects.json format (objects/object_bundle_writer.h LiftedObjectsJson; only
// "first_frame" (optional, default 0) and per frame "frame" and per object
// "category", "score", "track" and "keypoints_2d" are read). Its frames are
// the video's file frames counted from its first_frame.
#pragma once

#include <filesystem>
#include <vector>

#include "core/config.h"
#include "objects/box_keypoints.h"
#include "objects/objects_config.h"
#include "objects/objects_in_video.h"
#include "recon/bundle/bundle.h"

namespace doasido::objects {

// observations_dir is set but holds no file for the video (not permanent:
// the file can be made).
inline constexpr const char* kErrorObservationsMissing = "object_observations_missing";

// The clip's span in file frames: [first_frame, first_frame + frames).
struct FrameSpan {
  int first_frame = 0;
  int frames = 0;
};

// The observations of the span, frame 0 = span.first_frame (frames outside
// the span left out): the models' keypoints, or the observations file's.
// `hands` (may be null; file frames) is where the models also look beside
// the fingers ([objects.models] hand_proposals); `seeds` (file frames) where
// a person boxed the object (objects/object_prompts.h): the models start
// prompted tracks there (seeds outside the span are not used). Errors name
// the clip's video, the file and the field.
std::vector<ObjectObservation> DetectObjects(const std::filesystem::path& video, const FrameSpan& span,
                                             const ObjectsConfig& config,
                                             const HandsByFrame* hands = nullptr,
                                             const std::vector<SeedBox>& seeds = {});

// The hands of a hands-stage bundle (its metric joints projected by its K)
// as 2D keypoints per file frame (frame t of the bundle is file frame
// first_frame + t), pixels with the origin at the top-left pixel's corner.
HandsByFrame HandsFromBundle(const recon::ClipBundle& hands, int first_frame);

// The observations in `json` (the format above) within `span`. Throws
// Error("bad_observations") naming the file and the field.
std::vector<ObjectObservation> ObservationsFromJson(const Json& json, const FrameSpan& span,
                                                    const std::string& file);

}  // namespace doasido::objects
