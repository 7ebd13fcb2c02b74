// The hands stage's names and configuration: the stage name (its queue
// name, config section and artifact folder), the files it writes, and the
// [hands] section with its defaults and valid ranges.
#pragma once

#include <string>

#include "core/config.h"
#include "recon/bundle/bundle_location.h"

namespace doasido::hands {

inline constexpr const char* kHandsStageName = recon::kHandsStageFolder;
// Per frame and hand: the models' 2D keypoints, confidences and the fitted
// metric joints (hands/hand_keypoints_json.h). The bundle files beside it
// (meta.json, K.npz, hands.npz) are recon/bundle/bundle.h's.
inline constexpr const char* kKeypointsFile = "keypoints.json";
// meta.json's extra key: true when K came from the default field of view.
inline constexpr const char* kIntrinsicsAssumedKey = "intrinsics_assumed";
// meta.json's extra key: the size prior, whether the size is assumed, and
// per track the fitted hand length and palm width (hands/hand_skeleton_fit.h).
inline constexpr const char* kHandSizeKey = "hand_size";

// How the 2D keypoints of one clip become tracks (hands/hand_tracker.h).
struct TrackerConfig {
  double min_score = 0.5;  // hand presence below this is not a detection
  int max_gap_frames = 5;  // a hand unseen this long or less is filled in; longer splits the track
  double max_jump = 1.5;   // a detection continues a track when its centre moved less than
                           // this many hand sizes since the track was last seen
  int min_track_frames = 3;         // tracks with fewer observed frames are dropped (spurious)
  double duplicate_distance = 0.5;  // hands this close (mean keypoint distance over the
                                    // smaller's size) in one frame are one hand; 0: off
  // Two hands seen together whose handedness votes alike get their sides
  // from where they are in the image when their fingers lean up or down by
  // at least this fraction of the hand's size (hands/hand_tracker.h); 0:
  // the surer vote keeps its side.
  double min_arrangement_lean = 0.1;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(TrackerConfig, min_score, max_gap_frames, max_jump,
                                                min_track_frames, duplicate_distance,
                                                min_arrangement_lean)

// The skeleton fit of one track (hands/hand_skeleton_fit.h). Sigmas weigh
// each residual: a residual of one sigma costs as much as any other.
struct FitConfig {
  double reprojection_sigma = 0.03;   // keypoint noise, fraction of the hand's size in the image
  double huber = 2.0;                 // robust loss: quadratic up to this many sigmas
  double bone_sigma_m = 0.002;        // a bone's length against the track's constant length
  double shape_sigma_m = 0.01;        // wrist-relative joints against the model's 3D landmarks
  // The landmark model's world landmarks (metric, hand frame) as the fit's
  // shape and pose prior: the shape residual above, turned into the camera
  // by each frame's PnP pose. false: only reprojection, bones, size and
  // acceleration shape the hand (PnP still starts it). hands_bench synth
  // measures both.
  bool world_prior = true;
  double acceleration_sigma_ms2 = 4;  // joint acceleration, m/s^2
  int max_iterations = 50;
  // A frame whose PnP pose turns more than this from most of the poses
  // within 5 frames of it loses its pose (the mirror-pose ambiguity of a
  // nearly flat hand: measured flips of 170-175 degrees on 02_cups and
  // 03_blocks); its keypoints still count.
  double max_pnp_turn_deg = 60;
  // After the fit, the wrist of a track is cut where it moves or turns
  // faster than these between two frames; a piece of at most
  // `max_untrusted_run` frames (not the longest) is untrusted: its
  // keypoints are dropped and the fit fills it like a gap, or cuts it off
  // at the track's ends (hands/hand_outliers.h). A hand moving objects:
  // ~1.5 m/s and ~500 degrees/s at most (02_cups' fastest: 1.1 m/s).
  // 0 turns this and the mirrored 3D hands' check off (every frame trusted,
  // the stage as it was).
  int max_untrusted_run = 5;
  double max_wrist_speed_m_s = 3;
  double max_wrist_turn_deg_s = 720;
  // The hand's size, the one metric cue of a single view (docs/hands.md,
  // "Size"). "adult": the skeleton is an adult template hand
  // (hands/hand_skeleton_fit.h) times one scale per track, under a
  // log-normal prior centred on `hand_length_m` (wrist to the middle
  // fingertip along the bones) with relative spread `hand_length_sigma`;
  // depth follows from the reprojection. "model": the landmark model's own
  // median lengths, no prior (its metric size is 0.5-0.95 of an adult's on
  // the bundled real clips).
  std::string size_prior = "adult";
  double hand_length_m = 0.182;     // adults: men ~0.19, women ~0.175
  double hand_length_sigma = 0.06;  // the spread of adult hand lengths, relative
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(FitConfig, reprojection_sigma, huber, bone_sigma_m,
                                                shape_sigma_m, world_prior, acceleration_sigma_ms2,
                                                max_iterations, max_pnp_turn_deg, max_untrusted_run,
                                                max_wrist_speed_m_s, max_wrist_turn_deg_s,
                                                size_prior, hand_length_m, hand_length_sigma)

// The [hands] section.
struct HandsConfig {
  // Horizontal field of view assumed when neither a bundle's K nor the
  // list's fx/fy/cx/cy or fov columns give the intrinsics: a phone's main
  // camera filming 16:9 video sees about 65 degrees across.
  double default_fov_deg = 65;
  int max_hands = 2;
  int max_side = 640;              // frames are decoded at most this large for the models
  std::string backend = "native";  // runtime of the hand models: "native" or "wasm"
  std::string models = "full";  // "full", "lite" or "lite_landmark" (filters/hand_models.h)
  // While a hand is tracked, the palm detector looks for the others on every
  // palm_every-th frame (1: every frame, as MediaPipe's VIDEO mode); with no
  // hand tracked on every frame; after a hand is lost on every frame for
  // palm_every frames (filters::HandLandmarkerOptions).
  int palm_every = 10;
  // The wide search for hands the palm detector misses (zoomed windows,
  // the landmark model on the whole frame, low-contrast crops stretched;
  // filters::HandLandmarker): always on a still image; on video on the
  // first frame, then on every wide_search_every-th frame without a
  // tracked hand (one search: 0.1-0.3 CPU s; every 30 frames it added
  // 0.04-0.18 CPU s per video second on the first 150 frames of the real
  // clips, hands_bench real; every 150, about 5 s, keeps hand-less footage
  // near its budget). 0: stills only.
  int wide_search_every = 150;
  // The wide search also on this many frames from the one where a tracked
  // hand is lost, while fewer than max_hands are tracked (a fast hand,
  // blurred or half hidden by what it carries: 02_cups 286-296, the cup
  // lifted to the frame's top; docs/hands.md). On all of 02_cups: 3 and 10
  // both find that hand on 286-294 (0: none), the detection 6.0 / 9.1 /
  // 11.2 model s for 0 / 3 / 10; but 3 also adds finds elsewhere that
  // stretch a track's fitted hand to 21 cm and a wrist jump to 5.2 cm
  // (hands_stage_test's bounds), so it is off by default and on in the
  // demo's config. 0: off.
  int lost_wide_search = 0;
  TrackerConfig tracker;
  FitConfig fit;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(HandsConfig, default_fov_deg, max_hands, max_side,
                                                backend, models, palm_every, wide_search_every,
                                                lost_wide_search, tracker, fit)

// Valid ranges; throws Error("bad_config") naming section.key.
void CheckConfig(const HandsConfig& c, const std::string& section);

}  // namespace doasido::hands
