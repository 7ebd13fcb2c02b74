// Paying for the hand models only where they decide.
//
// With the learned detector and learned_detector.after_cheap_verdicts (the
// default), the one decode computes every signal as the analysis did
// before the learned detector existed (the built-in detector's boxes) and
// keeps in memory, at analysis size, the frames the models would see (the
// sampling rate, colour) and every frame's gray image: SampleKeeper. Then
// the cheap verdicts judge those signals with their stages' configs: shot
// boundary (no boxes involved) and camera motion (boxes only mask the
// hands out of the background). A clip one of them rejects is done: it
// cost what it cost without the models, clip.detector_note says why they
// did not run, and the signals that need the hands are absent
// (MarkHandSectionsNotMeasured): their stages record not_measured naming
// that verdict, and the clip stops at it with its reason, as it would with
// the models on every clip when the verdicts are taken in this order. A clip they keep gets the models on the samples of its
// kept shot only, and the signals that depend on where the hands are
// (interaction, out-of-frame, activity) are rebuilt from the learned boxes
// frame by frame as the decode would have (a sample's hands held until the
// next sample; frames outside the kept shot uncovered). Activity is not a
// cheap verdict: it measures motion where the hands are, which only the
// models know. No frame is decoded twice.
//
// Memory: the gray frames of the span, about 37 kB each at 256 x 144 (2.2
// MB per second of 60 fps video), bounded by learned_detector.keep_mb;
// past it the activity signal stays the built-in detector's and
// clip.detector_note says so.
#pragma once

#include <map>
#include <optional>
#include <string>

#include "filters/analyze.h"
#include "filters/verdict.h"

namespace doasido::filters {

// Copies of the frames at the learned detector's sampling rate.
class SampleKeeper : public FrameConsumer {
 public:
  explicit SampleKeeper(LearnedDetectorConfig config) : config_(std::move(config)) {}
  void Begin(const VideoGeometry& geometry) override;
  void Consume(FrameContext& context) override;
  // By ordinal (0-based position in the analysed span).
  const std::map<std::int64_t, AnalysisFrame>& samples() const { return samples_; }
  // Every frame's gray image by ordinal; empty when they did not fit keep_mb.
  const std::vector<cv::Mat>& grays() const { return grays_; }

 private:
  LearnedDetectorConfig config_;
  std::int64_t every_ = 1;
  std::map<std::int64_t, AnalysisFrame> samples_;
  std::vector<cv::Mat> grays_;
  double kept_mb_ = 0;
  bool grays_overflow_ = false;
};

// The first cheap verdict that rejects a clip: its stage and reason code.
struct CheapRejection {
  std::string stage, reason;
};

// The cheap verdicts on the analysis measurements `analysis`: nullopt when
// they keep the clip (then `kept` is its kept shot), else the first that
// rejects it.
std::optional<CheapRejection> CheapVerdictRejection(const Json& analysis,
                                                    const CheapVerdictConfigs& verdicts,
                                                    const std::string& clip, ShotSpan* kept);

// The sections the hand models measure (interaction, out_of_frame,
// activity): a clip `rejection` removed before the models ran has none of
// them in `measurements`, which name them under kNotMeasuredKey instead,
// so that their stages record not_measured rather than judge the built-in
// detector's boxes (filters/verdict.h).
void MarkHandSectionsNotMeasured(const CheapRejection& rejection, Json* measurements);

// Runs the learned detector on `keeper`'s samples inside `kept` and
// replaces the interaction, out-of-frame and activity signals, the
// detections and detection_source in `out` with the learned ones (and adds
// the "hands" section).
void RunHandModelsOnKeptShot(const SampleKeeper& keeper, const ShotSpan& kept,
                             const VideoGeometry& geometry, const AnalyzeConfig& config,
                             const std::string& clip, ClipAnalysis* out);

}  // namespace doasido::filters
