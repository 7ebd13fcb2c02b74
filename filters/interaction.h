// Interaction presence: is a hand holding or handling an object?
//
// Three sources of hand/object boxes, in order of preference:
//  1. The clip's detections with contact states (100DOH annotations, the
//     synthetic world's ground truth, or an external detector's output
//     stored by the hand_object_detector stage, stages/detector_stage.h).
//  2. An external detector command (the seam for a learned detector such as
//     100DOH's hand_object_detector), run by stage hand_object_detector before the
//     analysis pass. Contract:
//       - `command` is run by /bin/sh after replacing {video} (absolute path),
//         {first_frame}, {last_frame} (inclusive 0-based file frame indices;
//         last_frame is -1 for "to the end") and {output} (a file path the
//         command must create). Each substituted value is single-quoted.
//       - Exit status 0 means success; anything else is an error naming the
//         clip and the command.
//       - {output} is JSON Lines, one line per analysed frame, in the 100DOH
//         demo's column order, full-resolution pixels, 0-based, x2/y2
//         exclusive:
//           {"frame": 120,
//            "hand_dets": [[x1,y1,x2,y2,score,state,dx,dy,magnitude,lr], ...],
//            "obj_dets":  [[x1,y1,x2,y2,score], ...]}
//         state: 0 none, 1 self, 2 other person, 3 portable object,
//         4 stationary object; lr: 0 left, 1 right. Rows scoring below
//         min_score are dropped. Frames may be sparse (e.g. every 15th).
//     Example (100DOH's detector wrapped by a small script of the user's):
//       command = "python3 /opt/hod/doasido_detect.py --video {video}
//                  --first {first_frame} --last {last_frame} --every 15
//                  --out {output}"
//  3. Otherwise the built-in classical detector (BuiltinHandObjectDetector),
//     run inside the analysis pass. What it can do: find moving skin-coloured
//     regions (YCrCb skin range gated by frame differencing) and call the
//     largest ones hands, and call a moving non-skin region next to a hand,
//     away from where the hand itself moved, the object it holds (contact
//     state P). What it cannot do: tell hands from faces, arms or other
//     moving skin; see still hands (it holds the last boxes for a short
//     while); see objects that do not move; work under strong camera motion
//     or non-skin gloves. Treat its verdicts as a coarse pre-filter.
//
// Signals (analysis pass), per frame: covered (a source covered the frame),
// hands, objects, and contact: a bit mask of the hands' contact states
// (bit s set when some hand has state s; bit 5 when the state is unknown).
//
// Decision (DecideInteraction): a covered frame interacts when one of its
// hands has a state in `contact_states` (frames of the kept shot only, when
// the shot filter trimmed the clip). Pass when at least
// min_interaction_fraction of the covered frames interact, else reject
// "no_interaction"; flag "no_detections" when fewer than
// min_covered_fraction of the frames were covered.
#pragma once

#include <deque>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "filters/frame_analyzer.h"
#include "filters/verdict.h"

namespace doasido::filters {

// The stage's name: also its config section and its section of the
// analysis stage's measurements.
inline constexpr const char* kInteractionStageName = "interaction";
// Reason codes: reject without hand-object contact (no_detections, flag:
// filters/verdict.h).
inline constexpr const char* kReasonNoInteraction = "no_interaction";

struct BuiltinDetectorConfig {
  // Skin in YCrCb (8-bit), a common range for many skin tones.
  int y_min = 40;
  int cr_min = 135, cr_max = 175;
  int cb_min = 85, cb_max = 135;
  int motion_threshold = 12;     // gray levels
  int motion_gap = 2;            // compare frame t with frame t - gap
  double min_hand_area = 0.002;  // fraction of the frame
  double max_hand_area = 0.25;
  double min_hand_motion = 0.05;  // fraction of a skin region that moved
  double min_object_area = 0.0015;
  double contact_distance = 0.03;  // fraction of the image diagonal
  int max_hands = 2;
  int hold_frames = 15;                 // keep the last hands this long when nothing moves
  bool compensate_camera = true;        // undo a global shift (phase correlation) first ...
  double global_motion_fraction = 0.2;  // ... when this much of the frame changed
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(BuiltinDetectorConfig, y_min, cr_min, cr_max,
                                                cb_min, cb_max, motion_threshold, motion_gap,
                                                min_hand_area, max_hand_area, min_hand_motion,
                                                min_object_area, contact_distance, max_hands,
                                                hold_frames, compensate_camera,
                                                global_motion_fraction)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const BuiltinDetectorConfig& c, const std::string& section);

// The built-in classical detector (see the file comment). Writes each
// frame's boxes into FrameContext::boxes (so later consumers use them) and
// keeps them as Detection rows at full resolution, source
// "detector:builtin".
class BuiltinHandObjectDetector : public FrameConsumer {
 public:
  explicit BuiltinHandObjectDetector(BuiltinDetectorConfig config = {}) : config_(config) {}
  void Begin(const VideoGeometry& geometry) override { geometry_ = geometry; }
  void Consume(FrameContext& context) override;
  const std::vector<Detection>& detections() const { return detections_; }

 private:
  BuiltinDetectorConfig config_;
  VideoGeometry geometry_;
  std::deque<cv::Mat> grays_, skins_;
  FrameBoxes last_;
  std::int64_t last_seen_ = -1000000;
  std::vector<Detection> detections_;
};

// Per frame: covered by a detector (0/1), hands, objects, the contact
// states present (bit mask, bit 5 = a hand with no state and no object at
// it), and how many hands touch an object (states 3 "portable" and 4
// "stationary", or a hand without a state whose box meets an object's).
// in_contact is empty in analyses made before it was measured.
struct InteractionSignals {
  std::vector<int> covered, hands, objects, contact, in_contact;
};
Json ToJson(const InteractionSignals& s);
InteractionSignals InteractionSignalsFromJson(const Json& j);  // throws Error("bad_measurements")

class InteractionExtractor : public FrameConsumer {
 public:
  void Consume(FrameContext& context) override;
  const InteractionSignals& signals() const { return signals_; }

 private:
  InteractionSignals signals_;
};

struct InteractionConfig {
  std::vector<int> contact_states = {3};  // 3 = portable object (100DOH "P")
  double min_interaction_fraction = 0.2;
  double min_covered_fraction = 0.5;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(InteractionConfig, contact_states,
                                                min_interaction_fraction, min_covered_fraction)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const InteractionConfig& c, const std::string& section);

// Fraction of the covered frames among positions first..last (inclusive)
// with a hand in one of `contact_states`.
double InteractionFraction(const InteractionSignals& s, const std::vector<int>& contact_states,
                           std::int64_t first, std::int64_t last);

// The rule of stage "interaction" (see the file comment) on its
// measurements {"clip", "signals": the "interaction" section of the
// analysis, "shot"} (filters/verdict.h): reject "no_interaction", flag
// "no_detections", else pass. Throws Error("bad_measurements") when they
// lack a field it reads.
FilterVerdict DecideInteraction(const Json& measurements, const InteractionConfig& config);

inline constexpr const char* kExternalDetectorStageName = "hand_object_detector";
// Reason code: flag, no detector command is configured.
inline constexpr const char* kReasonNoDetector = "no_detector";

struct ExternalDetectorConfig {
  std::string command;  // empty: the stage passes without running anything
  double min_score = 0.5;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ExternalDetectorConfig, command, min_score)
// Valid ranges (filters/config_checks.cc); throws Error("bad_config").
void CheckConfig(const ExternalDetectorConfig& c, const std::string& section);

// Reads an external detector's JSON Lines output (format in the file
// comment). Throws Error("bad_detections") naming the file and line.
std::vector<Detection> ReadDetectorOutput(const std::filesystem::path& path, double min_score,
                                          const std::string& source);

// Runs `config.command` for one clip span and reads its output file
// `output`. Throws Error("detector_failed") naming the clip and command on a
// non-zero exit or a missing output file.
std::vector<Detection> RunExternalDetector(const ExternalDetectorConfig& config,
                                           const std::filesystem::path& video,
                                           std::int64_t first_frame, std::int64_t last_frame,
                                           const std::filesystem::path& output,
                                           const std::string& clip);

}  // namespace doasido::filters
