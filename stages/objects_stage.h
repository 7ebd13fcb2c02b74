// The `objects` queue stage: after `hands`, before `bundle`. It takes the
// category models' box keypoints for the clip's kept span (the hands
// stage's span: objects/object_detection.h DetectObjects, the seam the
// model half fills; until then the observations a file gives), lifts each
// object track to a metric 6D pose per frame with one size
// (objects/object_reconstruction.h: EPnP, the scale that puts the hands
// stage's touching fingertips on the box's surface, else the category's
// size prior, recorded as assumed; one Ceres smoothing per track) and
// writes the object part of a clip bundle into its artifact folder
// <artifacts>/<clip>/objects/ (objects/object_bundle_writer.h: meta.json,
// K.npz, object/mesh.obj, object/poses.npz, objects.json). The `bundle`
// stage adds that object to the hands stage's bundle when no list row or
// model command gives the clip its bundle (stages/clip_inputs.h).
//
// A clip whose list names a bundle is passed at once, measurement
// "skipped": that bundle wins. So is a clip without the hands stage's
// output (the span, K and the metric hands come from it).
//
// The clip's list row may box the object on a frame (column object_box,
// ingest/object_prompt.h): the models start a prompted track there and
// follow it (objects/box_tracker.h), for the objects their 2D detector
// misses.
//
// Verdicts: pass; pass with reason `no_known_object` when no track of a
// category the models know survives (only objects.json is written; the
// clip stays hand-only). Errors (clip named): object_observations_missing
// (observations_dir set, no file for the video: retried), bad_object_box
// (the prompt is malformed or names an unknown category: permanent),
// bad_observations (permanent), bad_bundle (the hands stage's output).
#pragma once

#include "objects/objects_config.h"
#include "stages/stage.h"

namespace doasido::stages {

inline constexpr const char* kReasonNoKnownObject = "no_known_object";

// Measurement keys.
inline constexpr const char* kMeasureObjectCategory = "category";  // the chosen track's, or "none"
inline constexpr const char* kMeasureObjectSize = "size_m";
inline constexpr const char* kMeasureScaleSource = "scale_source";
inline constexpr const char* kMeasureScaleAssumed = "scale_assumed";
inline constexpr const char* kMeasureContactFrames = "contact_frames";
inline constexpr const char* kMeasureContactResidual = "contact_residual_m";
inline constexpr const char* kMeasureObservations = "observations";
inline constexpr const char* kMeasureObservedFrames = "observed_frames";
inline constexpr const char* kMeasureFilledFrames = "filled_frames";
// Frames posed by the hand holding the object (objects/held_object.h), among the filled.
inline constexpr const char* kMeasureCarriedFrames = "carried_frames";
inline constexpr const char* kMeasureDegenerateFrames = "degenerate_frames";
inline constexpr const char* kMeasureTracks = "tracks";
inline constexpr const char* kMeasureUnknownCategories = "unknown_categories";
// The clip's object prompt (its list row's object_box): boxes given, and
// those on frames of the kept span (the others cannot start a track).
inline constexpr const char* kMeasurePromptBoxes = "prompt_boxes";
inline constexpr const char* kMeasurePromptBoxesInSpan = "prompt_boxes_in_span";

class ObjectsStage : public Stage {
 public:
  explicit ObjectsStage(objects::ObjectsConfig config = {});
  std::string Name() const override { return objects::kObjectsStageName; }
  Json Params() const override { return config_; }
  StageResult Run(const ClipContext& context) override;

 private:
  objects::ObjectsConfig config_;
};

}  // namespace doasido::stages
