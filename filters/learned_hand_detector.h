// The learned hand detector inside the analysis pass (HandLandmarker:
// MediaPipe Hands, native or through Node), for clips without annotations.
//
// It samples `sample_fps` frames per second of the span, finds up to
// `max_hands` hands with 21 keypoints each, and holds a sample's hands
// until the next sample (the landmarker itself tracks a hand from one
// sample to the next). A hand detector says where hands are, not that they
// hold something; the object evidence is what the hand touches: edges in
// discs around the fingertips that are not the hand's own outline (the hand
// is masked by its skeleton drawn thick). A hand against an empty
// background (a raised hand signing, a hand in the air) has none; fingers on
// a pencil, a cup, a trackpad or a guitar neck have some. A hand with
// evidence at or above `min_object_edges` is in contact with a portable
// object (100DOH state 3), and the box of those edges is that object's box;
// else it has no contact (state 0).
//
// A hand the models lose is kept where it was last seen (a hand behind a
// cup, or one the models miss for a moment, is still there); one lost
// within `border_reach` of the border is taken to be partly past it, and
// its box is extended to that border. So with this detector a lost hand
// makes a clip's frames "cut" (the out-of-frame filter flags them for a
// person), never "missing": the models cannot tell a hand that left from
// one they no longer see. A kept hand's contact counts for `hold_samples`
// samples, then as none.
//
// What it writes: each frame's hands into FrameContext::boxes (later
// consumers see them), Detection rows at full resolution (source
// "detector:learned"), and per sample the hands' boxes, scores, keypoints
// (pixels at full resolution) and world keypoints (metres) for the clip's
// measurements, where reconstruction and retargeting can use them.
#pragma once

#include <memory>
#include <vector>

#include "core/config.h"
#include "core/records.h"
#include "filters/activity.h"
#include "filters/frame_analyzer.h"
#include "filters/hand_landmarker.h"
#include "filters/hand_models.h"

namespace doasido::filters {

struct LearnedDetectorConfig {
  double sample_fps = 5;        // frames per second sent to the models
  int max_hands = 2;
  double min_score = 0.5;       // hand presence
  double fingertip_reach = 0.35;   // disc radius around a fingertip, in palm lengths
  double hand_thickness = 0.45;    // skeleton line width masking the hand, in palm lengths
  double min_object_edges = 0.04;  // edge pixels per disc pixel outside the hand
  int hold_samples = 1;
  double border_reach = 0.05;  // fraction of the width / height
  // The models' runtime: "native" (in process, XNNPACK) or "wasm" (Node,
  // TFLite's WebAssembly runtime; the reference). filters/hand_models.h.
  std::string backend = "native";
  // Which models of @mediapipe/hands: "full", "lite" or "lite_landmark"
  // (filters/hand_models.h). lite_landmark: the full palm detector and the
  // lite landmark model (146 M multiply-adds instead of 331 M), the same
  // verdicts on the labelled real footage; "lite" also swaps the palm
  // detector and lost one (docs/hand_models.md).
  std::string models = kModelsLiteLandmark;
  // Run the models only after the cheap verdicts (shot boundary and camera
  // motion, judged on the built-in detector's boxes in the one decode) keep
  // the clip, and only on its kept shot: filters/deferred_hand_models.h.
  // false: the models run in the decode, on every sample of every clip.
  bool after_cheap_verdicts = true;
  // Memory for the frames kept meanwhile (megabytes; see there).
  double keep_mb = 1024;
  // While a hand is tracked, the palm detector looks for the others on
  // every palm_every-th sample the models see (HandLandmarkerOptions::
  // palm_every; 1: every sample, as MediaPipe's VIDEO mode). With no hand
  // tracked, or a tracked one lost, it runs on that sample (lost_search 1:
  // the filters' verdicts measured the same with a longer search, and paid
  // for it).
  int palm_every = 5;
  // Sampling that follows the motion. A sample where, since the last sample
  // the models saw, at most still_changed_fraction of the pixels around
  // that sample's hands moved (the activity signal between the two frames:
  // hand boxes grown by activity.box_margin, the whole frame when it had
  // none, pixels changed by more than activity.pixel_threshold gray levels)
  // is still: it keeps the models' last hands without running them, for at
  // most 1 / still_sample_fps seconds. still_sample_fps = sample_fps: every
  // sample runs the models.
  double still_sample_fps = 1;
  double still_changed_fraction = 0.01;
  // The palm detector on a sample the models see with no hand tracked (it
  // costs three lite landmark runs; MediaPipe runs it on every such frame).
  // It runs on every no_hand_palm_every-th such sample (a hand coming in is
  // found up to no_hand_palm_every - 1 samples later), and only when at
  // least no_hand_changed_fraction of the frame changed (the activity
  // signal, whole frame) since the last hand-less sample it ran on: a hand
  // cannot appear where nothing changed (PalmGate). 1 and 0: every sample.
  // 1 (the default): the cadence gate is off. At 3 the palm detector missed
  // the hand on every third sample of two synthetic clips (seeds 41 and 23,
  // 320 x 240) and never found it, where the samples between would have:
  // the cascade then rejected them for no interaction and the full
  // measurement kept them (tests/filters_cascade_invariance_test.cc).
  int no_hand_palm_every = 1;
  double no_hand_changed_fraction = 0.01;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(LearnedDetectorConfig, sample_fps, max_hands,
                                                min_score, fingertip_reach, hand_thickness,
                                                min_object_edges, hold_samples, border_reach, backend, models,
                                                after_cheap_verdicts, keep_mb, palm_every,
                                                still_sample_fps, still_changed_fraction,
                                                no_hand_palm_every, no_hand_changed_fraction)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const LearnedDetectorConfig& c, const std::string& section);

// The object evidence above for `hand` in `gray` (keypoints in its pixels):
// the density of edges around the fingertips outside the hand, and the box
// of those edges (the part of the touched object the fingers reach; empty
// when there are none).
struct FingertipEvidence {
  double density = 0;
  cv::Rect2d box;
};
FingertipEvidence ObjectEdgesAtFingertips(const cv::Mat& gray, const LandmarkedHand& hand,
                                          const LearnedDetectorConfig& config);

// Frames between two samples (>= 1) at the clip's frame rate.
std::int64_t SampleEvery(const VideoGeometry& geometry, const LearnedDetectorConfig& config);
// The most frames a still sample may hold the models' last hands for
// (a multiple of SampleEvery; equal to it when thinning is off).
std::int64_t StillEvery(const VideoGeometry& geometry, const LearnedDetectorConfig& config);

// Whether the palm detector looks at a frame where no hand is tracked
// (LearnedDetectorConfig::no_hand_palm_every, no_hand_changed_fraction:
// both must hold).
class PalmGate {
 public:
  PalmGate(int every, double changed_fraction, ActivitySignalConfig activity)
      : every_(every), changed_fraction_(changed_fraction), activity_(activity) {}
  void Reset();
  // Call on each frame with no hand tracked, with its gray image: true when
  // the palm detector is to run on it (that frame becomes the reference).
  bool Look(const cv::Mat& gray);

 private:
  int every_;
  double changed_fraction_;
  ActivitySignalConfig activity_;
  cv::Mat looked_;  // the last hand-less frame the palm detector ran on
  int since_ = 0;   // hand-less frames since then
};

class LearnedHandDetector : public FrameConsumer {
 public:
  // Starts the landmarker (throws what HandLandmarker throws). `activity`:
  // the activity signal's settings, for the motion-following sampling.
  LearnedHandDetector(LearnedDetectorConfig config, const std::string& clip,
                      ActivitySignalConfig activity = {});
  void Begin(const VideoGeometry& geometry) override;
  void Consume(FrameContext& context) override;

  const std::vector<Detection>& detections() const { return detections_; }
  // {"sample_every", "samples": [{"frame", "ms", "hands": [{"score",
  //  "right", "object_edges", "box", "keypoints", "world"}]}],
  //  "ms_per_sample", "model_samples", "palm_gated"}: pixels at full
  // resolution. A still sample (no model run) has "held_from": the frame
  // whose hands it repeats, and ms 0; a sample with no hand tracked that
  // the palm gate kept from the palm detector has "palm_gated": true, no
  // hands and ms 0. ms_per_sample is over all samples, model_samples counts
  // the ones the models saw, palm_gated the gated ones.
  Json Measurements() const;

 private:
  void HoldMissedHands(FrameBoxes* found, std::vector<int>* age) const;
  void RunModels(FrameContext& context);
  void Settle(FrameContext& context, FrameBoxes found, std::vector<int> age);
  void AddDetection(const cv::Rect2d& box, const char* kind, double score, int contact,
                    std::int64_t frame);

  bool Still(const FrameContext& context) const;

  LearnedDetectorConfig config_;
  ActivitySignalConfig activity_;
  HandLandmarker landmarker_;
  PalmGate palm_gate_;
  VideoGeometry geometry_;
  std::int64_t every_ = 1;
  std::int64_t still_every_ = 1;
  // The last sample the models saw: its gray frame, position, the hands
  // the models found (before held ones are added) and their detections.
  cv::Mat seen_gray_;
  std::int64_t seen_ordinal_ = 0, seen_frame_ = 0;
  Json seen_hands_ = Json::array();
  FrameBoxes seen_found_;
  std::vector<Detection> seen_detections_;
  int model_samples_ = 0, palm_gated_ = 0;
  FrameBoxes last_;
  std::vector<int> last_age_;  // samples since each of last_'s hands was seen
  std::vector<Detection> detections_;
  Json samples_ = Json::array();
  double total_ms_ = 0;
};

}  // namespace doasido::filters
