// Draws one frame's hands from their keypoints.json entry (so the picture
// shows exactly what the file says): bones and joints of the 2D keypoints,
// right hands red, left hands blue, filled frames in thinner lines, the
// side and score beside the wrist.
#pragma once

#include <opencv2/core.hpp>

#include "core/config.h"

namespace doasido::hands {

// `frame_entry` is {"hands": [...]} of hands/hand_keypoints_json.h in pixels
// of a `width` x `height` input; `bgr` may be that input at another size
// (keypoints are scaled to it).
void DrawHands(cv::Mat& bgr, const Json& frame_entry, int width, int height);

}  // namespace doasido::hands
