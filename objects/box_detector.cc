#include "objects/box_detector.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace doasido::objects {

namespace {

// The graph's SsdAnchorsCalculator and TensorsToDetectionsCalculator options.
constexpr int kStrides[] = {16, 32, 64, 128, 256, 512};
constexpr int kLayers = 6;
constexpr float kMinScale = 0.2f, kMaxScale = 0.95f;
constexpr float kAspectRatios[] = {1.0f, 2.0f, 0.5f, 3.0f, 0.3333f};
constexpr float kCentreScale = 10.0f, kSizeScale = 5.0f;

float LayerScale(int layer) {
  return kMinScale + (kMaxScale - kMinScale) * static_cast<float>(layer) / (kLayers - 1);
}

std::vector<SsdAnchor> MakeAnchors() {
  std::vector<SsdAnchor> anchors;
  for (int layer = 0; layer < kLayers; ++layer) {
    const float scale = LayerScale(layer);
    std::vector<std::pair<float, float>> shapes;  // (scale, aspect ratio)
    if (layer == 0) {
      shapes = {{0.1f, 1.0f}, {scale, 2.0f}, {scale, 0.5f}};
    } else {
      for (float ratio : kAspectRatios) shapes.emplace_back(scale, ratio);
      const float next = layer == kLayers - 1 ? 1.0f : LayerScale(layer + 1);
      shapes.emplace_back(std::sqrt(scale * next), 1.0f);
    }
    const int cells = static_cast<int>(std::ceil(static_cast<float>(kDetectorInputSize) / kStrides[layer]));
    for (int y = 0; y < cells; ++y) {
      for (int x = 0; x < cells; ++x) {
        for (const auto& [s, ratio] : shapes) {
          const float root = std::sqrt(ratio);
          anchors.push_back({(x + 0.5f) / cells, (y + 0.5f) / cells, s * root, s / root});
        }
      }
    }
  }
  return anchors;
}

}  // namespace

const std::vector<SsdAnchor>& SsdAnchors() {
  static const std::vector<SsdAnchor> anchors = MakeAnchors();
  return anchors;
}

double BoxIoU(const cv::Rect2d& a, const cv::Rect2d& b) {
  const double inter = (a & b).area();
  const double uni = a.area() + b.area() - inter;
  return uni > 0 ? inter / uni : 0;
}

void DetectorInput(const cv::Mat& rgb, std::vector<float>* out) {
  cv::Mat small;
  cv::resize(rgb, small, cv::Size(kDetectorInputSize, kDetectorInputSize), 0, 0, cv::INTER_AREA);
  out->resize(static_cast<std::size_t>(kDetectorInputSize) * kDetectorInputSize * 3);
  cv::Mat as_float(kDetectorInputSize, kDetectorInputSize, CV_32FC3, out->data());
  small.convertTo(as_float, CV_32FC3, 2.0 / 255.0, -1.0);
}

std::vector<DetectedBox> DecodeDetections(const DetectorOutput& out,
                                          const std::vector<std::string>& labels,
                                          const std::vector<std::string>& categories,
                                          double min_score, double nms_iou, int max_boxes) {
  const std::vector<SsdAnchor>& anchors = SsdAnchors();
  std::vector<DetectedBox> candidates;
  for (int i = 0; i < kDetectorAnchors; ++i) {
    // The anchor's label is its best class; a box is kept only when that
    // label is an allowed one (the graph filters after labelling).
    const float* logits = out.logits.data() + static_cast<std::size_t>(i) * kDetectorClasses;
    const int best = static_cast<int>(std::max_element(logits + 1, logits + kDetectorClasses) - logits);
    const float score = 1.0f / (1.0f + std::exp(-logits[best]));
    if (score < min_score) continue;
    const ObjectCategory* category = CategoryOfLabel(labels.at(best));
    if (category == nullptr ||
        std::find(categories.begin(), categories.end(), category->name) == categories.end()) {
      continue;
    }
    const float* r = out.boxes.data() + static_cast<std::size_t>(i) * 4;
    const SsdAnchor& a = anchors[i];
    const double cy = r[0] / kCentreScale * a.h + a.cy, cx = r[1] / kCentreScale * a.w + a.cx;
    const double h = std::exp(r[2] / kSizeScale) * a.h, w = std::exp(r[3] / kSizeScale) * a.w;
    candidates.push_back({category->name, labels[best], score, cv::Rect2d(cx - w / 2, cy - h / 2, w, h)});
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const DetectedBox& a, const DetectedBox& b) { return a.score > b.score; });
  std::vector<DetectedBox> kept;
  for (const DetectedBox& c : candidates) {
    if (static_cast<int>(kept.size()) >= max_boxes) break;
    bool suppressed = false;
    for (const DetectedBox& k : kept) suppressed |= BoxIoU(c.box, k.box) > nms_iou;
    if (!suppressed) kept.push_back(c);
  }
  return kept;
}

}  // namespace doasido::objects
