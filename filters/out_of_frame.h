// Out of frame: are the hand and the object it touches inside the picture?
//
// Signals (analysis pass), per frame, from the frame's hand and object boxes
// (the clip's detections — 100DOH annotations, synthetic ground truth, an
// external detector — or the built-in detector; see frame_analyzer.h):
//   covered         1 when a detection source covered the frame
//   hands           number of hand boxes
//   hand_cut        1 when a hand box reaches the image border
//   object_needed   1 when a hand is in contact with an object (state P or F,
//                   or unknown state with an object box overlapping the hand)
//   object_missing  1 when an object is needed but no object box exists
//   object_cut      1 when the touched object's box (the object box closest
//                   to a contacting hand) reaches the border
// "Reaches the border" means within border_margin (fraction of the image
// width/height) of an edge.
//
// Decision (DecideOutOfFrame), over the covered frames (of the kept shot when
// the shot filter trimmed the clip):
//   expected hands  the largest hand count seen in >= 20% of those frames
//   missing         fewer hands than expected (a hand left the picture), or
//                   a needed object missing; hand counts are only trusted
//                   from sources that see every visible hand (annotations,
//                   ground truth, an external detector's output), not from
//                   the learned detector, which keeps a hand it lost and
//                   marks one lost at the border as cut instead
//   cut             a hand or the touched object reaches the border
// Reject "out_of_frame" when missing_fraction >= reject_missing_fraction or
// cut_fraction >= reject_cut_fraction; flag "out_of_frame" when
// missing_fraction >= flag_missing_fraction or cut_fraction >=
// flag_cut_fraction; flag "no_detections" when fewer than
// min_covered_fraction of the frames were covered. A hand box touching the
// border is common in good clips (the arm enters from outside the view), so
// by default cut frames only flag a clip for review and missing ones reject
// it.
//
// Known limit: a 100DOH annotation of a frame without any hand yields no
// detection rows, so such a frame counts as uncovered rather than "hand
// missing".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "filters/frame_analyzer.h"
#include "filters/verdict.h"

namespace doasido::filters {

// The stage's name: also its config section and its section of the
// analysis stage's measurements.
inline constexpr const char* kOutOfFrameStageName = "out_of_frame";
// Reason code: reject or flag, the hand or touched object leaves the frame
// (no_detections, flag: filters/verdict.h).
inline constexpr const char* kReasonOutOfFrame = "out_of_frame";

struct OutOfFrameSignalConfig {
  double border_margin = 0.005;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(OutOfFrameSignalConfig, border_margin)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const OutOfFrameSignalConfig& c, const std::string& section);

struct OutOfFrameSignals {
  std::vector<int> covered, hands, hand_cut, object_needed, object_missing, object_cut;
  // False when the boxes came from a source that can miss a visible hand
  // (FrameBoxes::complete): then fewer hands than expected is not "missing".
  bool hands_complete = true;
};
Json ToJson(const OutOfFrameSignals& s);
OutOfFrameSignals OutOfFrameSignalsFromJson(const Json& j);  // throws Error("bad_measurements")

// Index of the object box a hand touches (closest centre among boxes that
// overlap the hand grown by half its size), or -1.
int TouchedObject(const cv::Rect2d& hand, const std::vector<cv::Rect2d>& objects);

class OutOfFrameExtractor : public FrameConsumer {
 public:
  explicit OutOfFrameExtractor(OutOfFrameSignalConfig config = {}) : config_(config) {}
  void Begin(const VideoGeometry& geometry) override { geometry_ = geometry; }
  void Consume(FrameContext& context) override;
  const OutOfFrameSignals& signals() const { return signals_; }

 private:
  bool AtBorder(const cv::Rect2d& box) const;
  OutOfFrameSignalConfig config_;
  VideoGeometry geometry_;
  OutOfFrameSignals signals_;
};

struct OutOfFrameConfig {
  double reject_missing_fraction = 0.10;
  double flag_missing_fraction = 0.05;
  double reject_cut_fraction = 1.01;  // > 1: cut frames alone never reject
  double flag_cut_fraction = 0.65;
  double min_covered_fraction = 0.5;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(OutOfFrameConfig, reject_missing_fraction,
                                                flag_missing_fraction, reject_cut_fraction,
                                                flag_cut_fraction, min_covered_fraction)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const OutOfFrameConfig& c, const std::string& section);

struct OutOfFrameSummary {
  double covered_fraction = 0;
  int expected_hands = 0;
  double missing_fraction = 0;  // of covered frames
  double cut_fraction = 0;
  double out_fraction = 0;  // missing or cut
  double hand_missing_fraction = 0, hand_cut_fraction = 0;
  double object_missing_fraction = 0, object_cut_fraction = 0;
};
// Over positions first..last (inclusive); see the file comment.
OutOfFrameSummary SummarizeOutOfFrame(const OutOfFrameSignals& s, std::int64_t first,
                                      std::int64_t last);

// The rule of stage "out_of_frame" (see the file comment) on its
// measurements {"clip", "signals": the "out_of_frame" section of the
// analysis, "shot"} (filters/verdict.h): reject or flag "out_of_frame",
// flag "no_detections", else pass. Throws Error("bad_measurements") when
// they lack a field it reads.
FilterVerdict DecideOutOfFrame(const Json& measurements, const OutOfFrameConfig& config);

}  // namespace doasido::filters
