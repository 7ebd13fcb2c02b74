// The hands stage's output: the hand part of a clip bundle (recon/bundle/bundle.h,
// docs/clip_bundle.md), which recon's ReadBundle reads like any other:
//   meta.json       width, height, frames (the span's), fps, units "m",
//                   producers {"hands", "hand_fit", "K"}, and
//                   "intrinsics_assumed": true | false
//   K.npz           the constant K used
//   hands.npz       left_/right_valid (T) and left_/right_joints (T,21,3),
//                   camera frame, metres, OpenPose-21 (= MediaPipe) order;
//                   both sides always, a side never seen all invalid;
//                   invalid frames' joints are NaN
//   keypoints.json  hands/hand_keypoints_json.h
// Gap frames the fit filled are valid in hands.npz and marked "filled" in
// keypoints.json.
#pragma once

#include <filesystem>

#include "hands/hand_reconstruction.h"
#include "recon/bundle/bundle.h"

namespace doasido::hands {

recon::ClipBundle HandBundle(const DetectedFrames& detected, const HandsResult& result);

// Writes the files above into `dir` (created). Throws Error("io") naming
// the file.
void WriteHandBundle(const DetectedFrames& detected, const HandsResult& result,
                     const std::filesystem::path& dir);

}  // namespace doasido::hands
