// Hand-made 2D labels of real video frames and the keypoint accuracy
// measured against them (issue 38: PCK per video for the detector alone,
// the tracker and the fit; left/right swaps).
//
// A label file (bench/hand_labels/<name>.json), one per video, made by a
// person looking at the frames (never by the models):
//   {"video": "videos/02_cups.mp4",        // relative to ../shared/data
//    "labeller": "who", "frames": [
//      {"frame": 12,                        // file frame index
//       "hands": [{"side": "right",         // as the camera sees it
//                  "keypoints_2d": [[u, v], ... 21],   // MediaPipe order, pixels as displayed
//                  "visible": [true, ... 21]}]}]}      // optional; false = not labelled
// PCK@a: the share of labelled keypoints whose prediction lies within a
// times the labelled hand's box (the larger side of its keypoints' box).
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hands/hand_observation.h"
#include "hands/hand_reconstruction.h"

namespace doasido::hands {

struct LabelledHand {
  Side side = Side::kRight;
  std::array<Eigen::Vector2d, kJoints> uv;
  std::array<bool, kJoints> visible{};
};

// The corners of the box of a labelled hand's visible keypoints.
std::pair<Eigen::Vector2d, Eigen::Vector2d> VisibleBounds(const LabelledHand& hand);

struct LabelledFrame {
  int frame = 0;
  std::vector<LabelledHand> hands;
};

struct HandLabels {
  std::string video;
  std::string labeller;
  std::vector<LabelledFrame> frames;
};

// Throws Error("bad_labels") naming the file and the field.
HandLabels ReadHandLabels(const std::filesystem::path& file);

// One predicted hand in a frame: its side and 2D keypoints.
struct PredictedHand {
  Side side = Side::kRight;
  std::array<Eigen::Vector2d, kJoints> uv;
};

struct PckScore {
  int keypoints = 0;  // labelled keypoints
  int within_01 = 0, within_02 = 0;
  int hands = 0, missed = 0;  // labelled hands; those with no prediction near them
  int swaps = 0;              // labelled hands whose nearest prediction has the other side
  // Over the labelled keypoints of the hands found: the sum of their 2D
  // errors in pixels and in the labelled hand's box sizes, and their number.
  double error_px = 0, error_boxes = 0;
  int found_keypoints = 0;
  double MeanErrorPx() const { return found_keypoints ? error_px / found_keypoints : 0.0; }
  double MeanErrorBoxes() const { return found_keypoints ? error_boxes / found_keypoints : 0.0; }
  double Recall() const { return hands ? 1.0 - static_cast<double>(missed) / hands : 0.0; }
  double Pck01() const { return keypoints ? static_cast<double>(within_01) / keypoints : 0.0; }
  double Pck02() const { return keypoints ? static_cast<double>(within_02) / keypoints : 0.0; }
  void Add(const PckScore& o);
};

// Scores the predictions of one labelled frame: each labelled hand against
// the nearest predicted hand (mean keypoint distance; a prediction is used
// once); a hand without one within its box size counts as missed, its
// keypoints as outside every threshold.
PckScore ScoreFrame(const LabelledFrame& labels, const std::vector<PredictedHand>& predicted);

// One video's labels scored three ways (issue 38): every hand the models
// gave on the frame (side from their handedness), the tracker's hands
// (tracks' observations with the tracks' sides) and the fit (the fitted
// joints projected with the result's K). Labelled frames outside
// `detected` are skipped (labelled_frames counts those scored).
struct LabelScores {
  PckScore models, tracker, fit;
  int labelled_frames = 0;
};
LabelScores ScoreLabels(const HandLabels& labels, const DetectedFrames& detected,
                        const HandsResult& result);

}  // namespace doasido::hands
