// A held object rides with the hand that holds it where the box-landmark
// model loses it or reads it wrong. On 02_cups 286-294 (the person's left
// hand lifts a cup off the ball to the frame's top) the model gave no
// keypoints on six frames and, on the cup seen tilted into its mouth,
// keypoints a third of the cup's size, which put it 1.0-1.2 m away while
// the hand carrying it stayed at 0.6 m: the simulation had no object to
// carry (E_pos 0.27 m, in_hand_frames 2).
//
// A hand holds the object on an observed frame when one of its fingertips
// lies within `hold_distance_m` of the object's box (the box's surface,
// the fingertip offset taken off). From such a frame on, the object's pose
// in the hand's frame (wrist; index and little fingers' bases) is kept. On
// each next frame where that hand is seen:
//   - the object observed where the grip left it (within max_deviation_m,
//     and nearer there than where the hand would carry it): let go;
//   - observed in the hand's fingers near where the hand carries it: its
//     own pose, the grip taken again from it;
//   - else (not observed, or observed away from the fingers and from
//     where it was: a misreading) posed by the hand and marked carried
//     (and filled),
// for at most `max_frames` frames after the grip was last seen.
#pragma once

#include "objects/object_reconstruction.h"
#include "objects/objects_config.h"
#include "recon/bundle/bundle.h"

namespace doasido::objects {

// The hand's frame on one frame: origin the wrist, x towards the index
// finger's base, z the normal of the palm's plane (wrist, index and
// little fingers' bases), y = z x x. Throws nothing; a degenerate palm
// gives a frame with NaN.
Pose HandFrame(const recon::Joints21& joints);

// Nearest fingertip's distance to the surface of the box of `size` posed
// at `box` (0 inside), the fingertip offset not taken off.
double FingertipToBox(const recon::Joints21& joints, const Pose& box, const Vec3& size);

// Carries `track` with the hands of `hands` (left and right, camera frame)
// as above, at most `config.max_frames` frames after the last observed
// frame that set the grip; `fingertip_offset_m` is the tip keypoint's
// distance from the touching skin. Returns the number of frames it posed
// by a hand.
int CarryWithHands(ObjectTrack& track, const recon::ClipBundle& hands, const CarryConfig& config,
                   double fingertip_offset_m);

}  // namespace doasido::objects
