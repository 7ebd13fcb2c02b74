// What the hands stage does not take from the models as they give it
// (docs/hands.md, "Outliers"):
//  - a mirrored 3D hand: within a track the landmark model's metric 3D
//    landmarks become their own mirror image for runs of frames (on
//    02_cups, mostly where its handedness vote changes). No rotation turns
//    a mirrored hand into the hand, so PnP turns it over (170-180 degrees)
//    and the fit's shape term pulls the palm 40-55 degrees between frames.
//    Those frames keep their keypoints and lose their pose (the fit
//    carries their 3D across from the neighbours);
//  - untrusted frames: after the fit, a short run where the wrist moves or
//    turns faster than a hand can; their keypoints are dropped and the fit
//    fills them like a gap (FitConfig::max_untrusted_run,
//    max_wrist_speed_m_s, max_wrist_turn_deg_s).
#pragma once

#include <vector>

#include "core/geometry.h"
#include "hands/hand_tracker.h"

namespace doasido::hands {

using Joints = std::array<Vec3, kJoints>;

// How far the palm (the wrist and the five fingers' bases, nearly rigid)
// turns between two sets of joints: the angle of the best rotation of one
// onto the other, degrees.
double HandTurnDeg(const Joints& a, const Joints& b);

// Frames of `track` whose 3D landmarks are nearer the mirror image (z -> -z,
// then the best rotation, centred, RMS) than the shape itself of most of
// the last kHandednessVotes frames kept (each kept as the track's
// handedness); the handedness most frames show is the track's.
inline constexpr int kHandednessVotes = 3;
std::vector<bool> MirroredFrames(const Track& track);

// Frames of a fitted track (joints per frame, wrist = joint 0) to
// distrust: the track is cut where the wrist moves more than `max_move_m`
// or turns (HandTurnDeg) more than `max_turn_deg` between two frames;
// every piece of at most `max_run` frames but the longest piece is
// untrusted (none with `max_run` 0).
std::vector<bool> UntrustedFrames(const std::vector<Joints>& joints, double max_move_m,
                                  double max_turn_deg, int max_run);

// `track` without the observations of the frames `drop` marks (gaps for
// the fit to fill, marked in Track::untrusted), less its leading and
// trailing unobserved frames (first_frame moves). A track left without
// observations has no frames.
Track WithoutFrames(const Track& track, const std::vector<bool>& drop);

}  // namespace doasido::hands
