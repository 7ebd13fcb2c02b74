// Where to look for an object the 2D detector misses: beside the fingers of
// a hand. The hands stage finds hands well on real footage while the SSD
// detector scores 02_cups' red plastic cups under 0.2 as cups; a hand that
// handles something holds it between its thumb and fingers. So, as the
// hand landmarker's wide search accepts a hand candidate by the landmark
// model's own presence (filters/hand_landmarker.h), the box tracker tries
// square boxes about the grasp point (the mean of the thumb, index and
// middle fingertips), on a small grid of offsets and a few sizes, in units
// of the hand's palm length (wrist to the middle finger's base), and keeps
// the one the category's box-landmark model is surest of, if its presence
// passes the model's threshold (objects/box_tracker.h).
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace doasido::objects {

inline constexpr int kHandPoints = 21;  // MediaPipe hand keypoints (0 wrist, 9 middle base, tips 4 8 12 16 20)
// A hand's 2D keypoints, pixels of the frame as displayed.
using HandPoints2d = std::array<Eigen::Vector2d, kHandPoints>;

struct HandProposalConfig {
  // Box sides, in palm lengths (a cup is about as tall as a hand is long,
  // about two palm lengths).
  std::vector<double> sizes = {1.6, 2.4};
  // Box centres on a 3 x 3 grid about the grasp point, this many palm
  // lengths apart (0: the grasp point only).
  double offset = 0.5;
};

// The candidate boxes for one hand, in its pixels; none for a hand whose
// palm is shorter than `min_palm_px` (too small to hold a visible object).
std::vector<cv::Rect2d> HandProposals(const HandPoints2d& hand, const HandProposalConfig& config,
                                      double min_palm_px = 8.0);

}  // namespace doasido::objects
