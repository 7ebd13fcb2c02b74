// Draws one frame's objects from their JSON entry (objects/box_keypoints_json.h,
// so the picture shows exactly what the file says): the 12 edges of each
// box (front face, keypoints 2 4 6 8, thicker), its centre, and the
// category, score and track beside it; one colour per track.
#pragma once

#include <opencv2/core.hpp>

#include "core/config.h"

namespace doasido::objects {

// `frame_entry` is {"objects": [...]} in pixels of a `width` x `height`
// input; `bgr` may be that input at another size (keypoints are scaled).
void DrawObjects(cv::Mat& bgr, const Json& frame_entry, int width, int height);

}  // namespace doasido::objects
