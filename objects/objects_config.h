// The objects stage's names and configuration: the stage name (its queue
// name, config section and artifact folder), the file it writes beside the
// bundle parts, and the [objects] section with its defaults and ranges.
#pragma once

#include <string>

#include "core/config.h"
#include "objects/box_keypoints_config.h"
#include "recon/bundle/bundle_location.h"

namespace doasido::objects {

inline constexpr const char* kObjectsStageName = recon::kObjectsStageFolder;
// Per frame and object: the keypoints, the metric pose and size, what was
// assumed (objects/object_bundle_writer.h).
inline constexpr const char* kObjectsFile = "objects.json";
// Where a track's size came from (objects.json "scale_source", the
// bundle's producers "object_scale").
inline constexpr const char* kScaleFromHand = "hand_contact";
inline constexpr const char* kScaleFromPrior = "category_prior";

// One Ceres problem per track (objects/object_track_fit.h). Sigmas weigh
// each residual as in [hands.fit].
struct ObjectFitConfig {
  double reprojection_sigma = 0.03;         // keypoint noise, fraction of the box's image size
  double huber = 2.0;                       // in sigmas
  double acceleration_sigma_ms2 = 4;        // the centre's acceleration (the hands' figure)
  double angular_acceleration_sigma = 60;   // rad/s^2
  int max_iterations = 50;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ObjectFitConfig, reprojection_sigma, huber,
                                                acceleration_sigma_ms2,
                                                angular_acceleration_sigma, max_iterations)

// A held object carried by its hand where the model loses it or reads it
// wrong (objects/held_object.h).
struct CarryConfig {
  double hold_distance_m = 0.02;  // fingertip to the box's surface (offset taken off): holding
  double max_deviation_m = 0.1;   // observed this far from the hand and from where it was: misread
  int max_frames = 30;            // carried at most this long after the grip was last seen; 0: off
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(CarryConfig, hold_distance_m, max_deviation_m,
                                                max_frames)

// The [objects] section.
struct ObjectsConfig {
  // Where the box keypoints come from (objects/object_detection.h): empty
  // runs the category models in process ([objects.models]); a folder reads
  // `<video stem>.json` files in the `doasido objects` format instead (a
  // user's own detector, or keypoints corrected by hand).
  std::string observations_dir;
  BoxKeypointsConfig models;  // [objects.models]: the detector, trackers and thresholds
  double min_score = 0.5;      // box-landmark presence below this is no observation
  int min_track_frames = 5;    // shorter tracks are dropped
  int max_gap_frames = 10;     // longer runs without the object split the fitted track
  double degenerate_ratio = 0.2;  // thinnest / largest lifted extent below this: a thin slab
  int min_contact_frames = 5;     // frames with a fingertip on the box before the hand sets the size
  double fingertip_offset_m = 0.008;  // the tip keypoint's distance from the touching skin
  double contact_robust_m = 0.01;     // Cauchy scale of a fingertip's distance to the surface
  double max_contact_residual_m = 0.02;  // a contact fit whose median is worse falls back to the prior
  int cylinder_segments = 48;
  ObjectFitConfig fit;
  CarryConfig carry;  // [objects.carry]
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ObjectsConfig, observations_dir, min_score,
                                                min_track_frames, max_gap_frames, degenerate_ratio,
                                                min_contact_frames, fingertip_offset_m,
                                                contact_robust_m, max_contact_residual_m,
                                                cylinder_segments, fit, models, carry)

// Valid ranges; throws Error("bad_config") naming section.key.
void CheckConfig(const ObjectsConfig& c, const std::string& section);

}  // namespace doasido::objects
