// How the objects stage finds the 2D box keypoints (objects/box_tracker.h):
// which Objectron categories run, how often the 2D detector runs, and the
// thresholds of MediaPipe's Objectron graph (objectron_cpu.pbtxt,
// object_detection_oid_v4_cpu.pbtxt, box_landmark_cpu.pbtxt in
// google/mediapipe's modules/objectron), its published defaults.
#pragma once

#include <string>
#include <vector>

#include "core/config.h"

namespace doasido::objects {

struct BoxKeypointsConfig {
  // Box-landmark models to run, by category (objects/objectron_models.h):
  // a detection of another category's labels is ignored.
  std::vector<std::string> categories = {"cup", "sneakers", "chair", "camera"};
  int max_objects = 5;  // tracks at once (objectron.py's max_num_objects)
  // MediaPipe runs the detector whenever fewer than max_objects are tracked,
  // i.e. on nearly every frame (1 and 1 here). Here it runs on the frame a
  // track is lost, every idle_detect_every-th frame while nothing is tracked
  // (an object that comes into view is found that many frames late at
  // most), and every detect_every-th frame otherwise. The detector is ~23 ms
  // a run, the box-landmark model ~11 (docs/benchmarks.md).
  int detect_every = 10;
  int idle_detect_every = 5;
  double min_detection_score = 0.5;  // sigmoid class score of a detection
  double nms_iou = 0.5;              // non-maximum suppression, intersection over union
  // A detection whose box overlaps a tracked object's by more than this
  // (IoU) is that object (the graph's association threshold).
  double same_object_iou = 0.2;
  // Presence below this ends a track (box_landmark_cpu.pbtxt's threshold).
  double min_presence = 0.99;
  // The landmark crop: the box (detected, or the last keypoints' extent)
  // enlarged this much and squared on its long side.
  double crop_scale = 1.5;
  int max_side = 640;  // frames are decoded at most this large for the models
  // Boxes beside a hand's fingers (objects/hand_proposals.h), tried with
  // the box-landmark model of each category when hands are given
  // (BoxTracker::NearHands), every hand_proposal_every-th frame while that
  // hand holds no tracked object: for the objects the detector misses.
  // Off by default: the cup model's presence passes 0.99 on hands too (on
  // asl_hand, no cup in sight, 32 short "cup" tracks), and on 02_cups and
  // cup.mp4 the box it keeps is rough (docs/object_models.md).
  bool hand_proposals = false;
  int hand_proposal_every = 10;
  std::vector<double> hand_proposal_sizes = {1.6, 2.4};  // box sides, palm lengths
  double hand_proposal_offset = 0.5;                     // grid step, palm lengths
  // A box found beside a hand continues the track of that category lost
  // within this many frames whose last box's centre it lies near (within
  // the lost box enlarged twice): a held object stays one track while the
  // model loses and finds it again. 0 (off) by default: on cup.mp4 30 made
  // one 60-frame track of the rough boxes, and dynamics retargeting did
  // worse on it than on the 35-frame one (docs/objects.md).
  int hand_rejoin_frames = 0;
  // A track a person prompted (BoxTracker::Seed: a list row's object_box, the
  // command's --seed) is followed in 2D from its box (objects/box_follower.h,
  // median flow) rather than from the model's own keypoints, which on held
  // or upside-down cups shrink onto part of the cup and lose it within a few
  // frames (docs/object_models.md). The model still gives each frame's
  // keypoints where its presence passes min_presence; the track ends after
  // this many frames in a row without them, or where the 2D follower fails.
  int prompt_max_missing_frames = 15;
  // The follower (BoxFollowerConfig): the box's long side on its grey frame
  // (pixels), points per side of its grid, the forward-backward error a
  // point may have (pixels of that frame) and the fraction of the grid that
  // must follow, else the track ends.
  int prompt_follow_side = 48;
  int prompt_follow_grid = 10;
  double prompt_follow_max_error = 1.0;
  double prompt_follow_min_points = 0.25;
  // The guard against following the wrong object: the track ends where the
  // model's keypoint centre lies further than this (times the followed box's
  // long side) from the followed box's centre or from the keypoint centre
  // of the last frame they were seen. The box is not moved onto the
  // keypoints: on 02_cups' lowered cup their centre lags the cup, and moved
  // there the box lost it for 15 frames (docs/objects.md).
  double prompt_max_jump = 0.5;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(BoxKeypointsConfig, categories, max_objects,
                                                detect_every, idle_detect_every, min_detection_score, nms_iou,
                                                same_object_iou, min_presence, crop_scale, max_side,
                                                hand_proposals, hand_proposal_every, hand_proposal_sizes,
                                                hand_proposal_offset, hand_rejoin_frames,
                                                prompt_max_missing_frames, prompt_follow_side, prompt_follow_grid,
                                                prompt_follow_max_error, prompt_follow_min_points, prompt_max_jump)

// Valid ranges; throws Error("bad_config") naming section.key.
void CheckConfig(const BoxKeypointsConfig& c, const std::string& section);

}  // namespace doasido::objects
