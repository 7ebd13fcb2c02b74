#include "filters/frame_analyzer.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <limits>
#include <opencv2/imgproc.hpp>

namespace doasido::filters {

DetectionIndex::DetectionIndex(const std::vector<Detection>& detections, double full_to_analysis,
                               std::int64_t single_gap)
    : max_gap_(single_gap) {
  for (const Detection& d : detections) {
    FrameBoxes& boxes = by_frame_[d.frame];
    boxes.known = true;
    const cv::Rect2d box(d.x1 * full_to_analysis, d.y1 * full_to_analysis,
                         (d.x2 - d.x1) * full_to_analysis, (d.y2 - d.y1) * full_to_analysis);
    if (d.kind == "hand") {
      boxes.hands.push_back(box);
      boxes.hand_contact.push_back(d.contact_state);
    } else {
      boxes.objects.push_back(box);
    }
  }
  if (by_frame_.size() >= 2) {
    std::vector<std::int64_t> spacing;
    for (auto it = std::next(by_frame_.begin()); it != by_frame_.end(); ++it) {
      spacing.push_back(it->first - std::prev(it)->first);
    }
    std::nth_element(spacing.begin(), spacing.begin() + spacing.size() / 2, spacing.end());
    end_gap_ = spacing[spacing.size() / 2] - 1;
    max_gap_ = spacing[spacing.size() / 2] / 2;
  }
}

FrameBoxes DetectionIndex::Lookup(std::int64_t frame) const {
  if (by_frame_.empty()) return {};
  auto after = by_frame_.lower_bound(frame);
  const FrameBoxes* best = nullptr;
  std::int64_t best_gap = std::numeric_limits<std::int64_t>::max();
  if (after != by_frame_.end()) {
    best_gap = after->first - frame;
    best = &after->second;
  }
  if (after != by_frame_.begin()) {
    auto before = std::prev(after);
    if (frame - before->first < best_gap) {
      best_gap = frame - before->first;
      best = &before->second;
    }
  }
  // Before the first and after the last annotated frame the next annotation
  // would have come a whole spacing later.
  const bool outside = after == by_frame_.end() || after == by_frame_.begin();
  const std::int64_t allowed = outside ? std::max(max_gap_, end_gap_) : max_gap_;
  if (best == nullptr || best_gap > allowed) {
    FrameBoxes none;
    none.known = true;
    return none;
  }
  return *best;
}

AnalysisSummary AnalyzeFrames(const std::filesystem::path& path, const DecoderOptions& options,
                              const std::vector<Detection>& detections,
                              const std::vector<FrameConsumer*>& consumers) {
  VideoDecoder decoder(path, options);
  AnalysisSummary summary;
  summary.geometry = decoder.geometry();
  summary.first_frame = decoder.first_frame();
  const double fps = summary.geometry.fps > 0 ? summary.geometry.fps : 30.0;
  // 100DOH frames are 2 s apart: each annotation covers 1 s either side.
  const DetectionIndex index(detections, 1.0 / summary.geometry.downscale,
                             static_cast<std::int64_t>(std::lround(fps)));
  for (FrameConsumer* consumer : consumers) consumer->Begin(summary.geometry);
  AnalysisFrame frame;
  FrameContext context;
  while (decoder.Next(&frame)) {
    context.frame = &frame;
    context.ordinal = summary.frames;
    cv::cvtColor(frame.bgr, context.gray, cv::COLOR_BGR2GRAY);
    context.boxes = index.Lookup(frame.index);
    for (FrameConsumer* consumer : consumers) consumer->Consume(context);
    ++summary.frames;
  }
  for (FrameConsumer* consumer : consumers) consumer->Finish();
  return summary;
}

}  // namespace doasido::filters
