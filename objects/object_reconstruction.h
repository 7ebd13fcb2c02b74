// From a clip's box keypoints to each object's metric 6D pose per frame:
//   1. observations grouped by track (one category each; presence under
//      min_score dropped; unknown categories and short tracks left out);
//   2. each frame lifted up to scale (objects/box_lifting.h); the track's
//      box proportions are the median of its frames' (a round object's
//      cylinder takes the mean of the box's two widths as its diameter);
//      frames whose box is a thin slab are marked degenerate (for a round
//      object its axis still counts: SideViewPose);
//   3. every frame's pose for the track's proportions, up to scale;
//   4. the scale (objects/object_scale.h): from the fingertips of the hands
//      stage's metric hands that project inside the box on at least
//      min_contact_frames frames, else the category's prior, recorded as
//      assumed;
//   5. one smoothing fit per run of frames without a gap over
//      max_gap_frames (objects/object_track_fit.h), gaps filled and marked;
//      round objects' yaw made one convention (objects/box_lifting.h
//      CanonicalYaw): the models' yaw of a cup is not an observation;
//   6. a held object carried by the hand holding it where the model loses
//      it or reads it wrong (objects/held_object.h, [objects.carry]).
// Everything in the camera frame of the frames as displayed, metres.
#pragma once

#include <string>
#include <vector>

#include "core/geometry.h"
#include "objects/box_keypoints.h"
#include "objects/box_lifting.h"
#include "objects/objects_config.h"
#include "recon/bundle/bundle.h"

namespace doasido::objects {

// One frame of a track. Frames outside the track's fitted runs have no pose.
struct ObjectFrame {
  bool posed = false;
  Pose pose;                 // object (box centre, box axes) -> camera, metres
  bool observed = false;     // the model saw the object (keypoints below)
  bool filled = false;       // posed by the fit across a gap, or carried
  bool carried = false;      // posed by the hand holding it (objects/held_object.h)
  bool degenerate = false;   // the frame's lifted box is a thin slab
  float score = 0;
  BoxKeypoints keypoints{};  // when observed, as the record gives them
};

struct ObjectTrack {
  int track = 0;
  std::string category;
  bool symmetric = false;       // round about the box's y axis: a cylinder, yaw not observed
  Vec3 size_m = Vec3::Zero();   // extents along the box's x, y, z (x = z = diameter when round)
  bool scale_assumed = true;    // the category prior, not the hand
  std::string scale_source;     // kScaleFromHand or kScaleFromPrior
  int contact_frames = 0;       // frames with a fingertip inside the box's image
  double contact_residual_m = 0;  // median fingertip distance to the surface at the fitted size
  std::vector<ObjectFrame> frames;  // (T) one per frame of the clip's span
  int ObservedFrames() const;
  int PosedFrames() const;
};

struct ObjectsResult {
  std::vector<ObjectTrack> tracks;
  int chosen = -1;  // the track written as the bundle's object: most contact, then most seen
  std::vector<std::string> unknown_categories;  // seen, but no model prior: left out
  int dropped_short_tracks = 0;
};

// `hands` is the hands stage's bundle for the same span (its frames, K, fps
// and metric hands). Throws Error("bad_keypoints") naming the frame for an
// observation outside [0, frames).
ObjectsResult ReconstructObjects(const std::vector<ObjectObservation>& observations,
                                 const recon::ClipBundle& hands, const ObjectsConfig& config);

}  // namespace doasido::objects
