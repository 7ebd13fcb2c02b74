// The 2D stage of Objectron: the SSD detector's input tensor and the
// decoding of its raw outputs into boxes, as MediaPipe's graph
// (object_detection_oid_v4_cpu.pbtxt) does: the whole frame stretched to
// 300 x 300 in [-1, 1]; 1917 SSD anchors; per anchor its best class (class
// 0 ignored) after a sigmoid; box offsets scaled by 10, 10, 5, 5 (centre y,
// x; log height, width); boxes of allowed labels above the score threshold;
// greedy non-maximum suppression by intersection over union.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "objects/objectron_models.h"

namespace doasido::objects {

// One SSD anchor, in [0, 1] of the detector's input.
struct SsdAnchor {
  float cx = 0, cy = 0, w = 0, h = 0;
};
// The 1917 anchors of SsdAnchorsCalculator with the graph's options: six
// layers of strides 16..512 (19, 10, 5, 3, 2, 1 cells), scales 0.2..0.95,
// aspect ratios 1, 2, 0.5, 3, 0.3333 and one of scale sqrt(s_i s_i+1) per
// cell; the lowest layer only (0.1, 1), (s_0, 2), (s_0, 0.5).
const std::vector<SsdAnchor>& SsdAnchors();

struct DetectedBox {
  std::string category;  // the box-landmark model it selects (ObjectCategory::name)
  std::string label;     // the detector's Open Images label
  float score = 0;       // 0..1
  cv::Rect2d box;        // [0, 1] of the frame (x right, y down)
};

// The detector's input for an RGB frame of 8-bit pixels: 300 x 300 x 3
// floats in [-1, 1], the frame stretched (its aspect ratio not kept).
void DetectorInput(const cv::Mat& rgb, std::vector<float>* out);

// Boxes of the categories in `categories`, best first, at most `max_boxes`.
std::vector<DetectedBox> DecodeDetections(const DetectorOutput& out,
                                          const std::vector<std::string>& labels,
                                          const std::vector<std::string>& categories,
                                          double min_score, double nms_iou, int max_boxes);

// Intersection over union of two boxes (0 when both are empty).
double BoxIoU(const cv::Rect2d& a, const cv::Rect2d& b);

}  // namespace doasido::objects
