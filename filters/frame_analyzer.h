// The single decode pass that feeds every filter.
//
// AnalyzeFrames decodes a clip once (video/video_decoder.h) and hands each
// analysis-resolution frame, with the work every consumer shares (the gray
// image and the hand/object boxes of that frame), to a list of consumers in
// order. Consumers keep their own per-frame signals; they never decode.
//
// Boxes: hand and object boxes come from the clip's detections (100DOH
// annotations, the synthetic world or an external detector) mapped to
// analysis pixels, or from a consumer earlier in the list that detects them
// itself (the built-in interaction detector writes FrameContext::boxes).
#pragma once

#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <vector>

#include "core/records.h"
#include "video/video_decoder.h"

namespace doasido::filters {

// Boxes of one frame at analysis resolution.
struct FrameBoxes {
  std::vector<cv::Rect2d> hands;
  std::vector<cv::Rect2d> objects;
  std::vector<int> hand_contact;  // contact state per hand (-1 unknown)
  bool known = false;             // false: no detector covered this frame
  bool complete = true;           // false: the source can miss a visible hand
};

struct FrameContext {
  const AnalysisFrame* frame = nullptr;
  std::int64_t ordinal = 0;  // 0-based position of the frame in the clip span
  cv::Mat gray;              // CV_8U, analysis size (COLOR_BGR2GRAY)
  FrameBoxes boxes;          // consumers earlier in the list may fill this in
};

class FrameConsumer {
 public:
  virtual ~FrameConsumer() = default;
  // Called once before the first frame.
  virtual void Begin(const VideoGeometry& geometry) { (void)geometry; }
  // Called for every frame of the span in order. May modify context.boxes
  // (later consumers see the change).
  virtual void Consume(FrameContext& context) = 0;
  // Called once after the last frame.
  virtual void Finish() {}
};

// Clip detections indexed by frame, for looking up the boxes of a frame.
// Sources differ in density: 100DOH annotates one frame in 60, a detector or
// the synthetic world every frame. A frame takes the boxes of the nearest
// frame with detections within half the median spacing of such frames
// (`single_gap` when only one frame has any); farther than that it has no
// boxes, i.e. no hand was found there (before the first and after the last
// such frame the allowance is a whole spacing). Every frame counts as covered when
// the clip has any detection.
class DetectionIndex {
 public:
  DetectionIndex() = default;
  DetectionIndex(const std::vector<Detection>& detections, double full_to_analysis,
                 std::int64_t single_gap);
  bool empty() const { return by_frame_.empty(); }
  std::int64_t max_gap() const { return max_gap_; }
  // Boxes at analysis resolution for file frame `frame`.
  FrameBoxes Lookup(std::int64_t frame) const;

 private:
  std::map<std::int64_t, FrameBoxes> by_frame_;
  std::int64_t max_gap_ = 0;
  std::int64_t end_gap_ = 0;
};

struct AnalysisSummary {
  VideoGeometry geometry;
  std::int64_t first_frame = 0;  // file index of the first analysed frame
  std::int64_t frames = 0;       // frames analysed
};

// Decodes `path` over the span in `options` once and feeds every frame to
// `consumers` in order. Boxes are pre-filled from `detections` (may be
// empty). Throws what VideoDecoder throws.
AnalysisSummary AnalyzeFrames(const std::filesystem::path& path, const DecoderOptions& options,
                              const std::vector<Detection>& detections,
                              const std::vector<FrameConsumer*>& consumers);

}  // namespace doasido::filters
