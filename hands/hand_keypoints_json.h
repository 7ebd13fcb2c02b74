// keypoints.json, the hands' per-frame record that people and other tools
// read (the `doasido hands` command writes the same per input):
//
//   {"width", "height", "fps", "first_frame" (the file frame of frame 0),
//    "K" [[3x3]], "intrinsics_source", "intrinsics_assumed",
//    "joint_order": "mediapipe21",
//    "frames": [{"frame": i, "hands": [{"side": "right" | "left",
//        "track": n, "score": s, "filled": bool, "untrusted": bool,
//        "keypoints_2d": [[u, v] x 21], "confidence": [21 values],
//        "joints_camera": [[x, y, z] x 21]}]}]}
//
// One entry per frame of the input, hands possibly empty. Keypoints are
// pixels of the input as displayed (the models' keypoints; on a filled frame
// the fitted joints' projection, with confidence 0 and score 0; an
// untrusted frame, hands/hand_outliers.h, is filled too), joints are
// metres in the camera frame (x right, y down, z forward) after the fit.
// MediaPipe's joint order: 0 wrist, 1-4 thumb, 5-8 index, 9-12 middle,
// 13-16 ring, 17-20 little finger.
#pragma once

#include <filesystem>
#include <string>

#include "core/config.h"
#include "hands/hand_reconstruction.h"

namespace doasido::hands {

Json KeypointsJson(const DetectedFrames& detected, const HandsResult& result);

// Writes `text` to `path` through a temporary file renamed into place (a
// reader never sees half a file). Throws Error("io") naming the file.
void WriteTextFile(const std::filesystem::path& path, const std::string& text);

}  // namespace doasido::hands
