// A prompted box followed in 2D from frame to frame, median-flow style
// (Kalal, Mikolajczyk, Matas, "Forward-Backward Error: Automatic Detection
// of Tracking Failures", ICPR 2010): a grid of points inside the box is
// tracked by pyramidal Lucas-Kanade (cv::calcOpticalFlowPyrLK) on a grey
// frame shrunk so that the box's long side is a few dozen pixels, each point
// tracked back again; the points that come back to where they started (the
// forward-backward error) move the box by their median displacement and
// scale it by the median change of their pairwise distances. Too few such
// points and the follower says the box is lost.
//
// The follower has no model of what it follows: it keeps no appearance
// and cannot jump to a look-alike elsewhere in the frame, unlike a
// detector-style tracker (OpenCV's MIL, which on 02_cups' shrunk frames
// wandered onto the other red cups, docs/objects.md). Whether the box still
// holds the object is the box-landmark model's say (objects/box_tracker.h).
//
// Contract: Start() takes an RGB (or BGR) 8-bit frame and a box in its
// pixels; Follow() takes the next frame of the same size and returns false
// when the box is lost, else the box moved.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace doasido::objects {

struct BoxFollowerConfig {
  int side = 48;           // the box's long side on the follower's grey frame, pixels
  int grid = 10;           // points per side of the box's grid
  double max_error = 1.0;  // forward-backward error a point may have, pixels of the follower's frame
  double min_points = 0.25;  // fraction of the grid that must follow, else the box is lost
};

class BoxFollower {
 public:
  explicit BoxFollower(BoxFollowerConfig config) : config_(config) {}
  void Start(const cv::Mat& frame, const cv::Rect2d& box);
  bool Follow(const cv::Mat& frame);
  const cv::Rect2d& box() const { return box_; }

 private:
  cv::Mat Grey(const cv::Mat& frame) const;

  BoxFollowerConfig config_;
  double scale_ = 1.0;  // the follower's frame: the caller's times this, fixed at Start
  cv::Mat previous_;    // grey, shrunk
  cv::Rect2d box_;      // the caller's pixels
  std::vector<cv::Point2f> from_, to_, back_;  // reused between frames
};

}  // namespace doasido::objects
