// The learned hand detector: MediaPipe Hands (palm detector + 21-keypoint
// landmark model). The models run on one of two runtimes
// (filters/hand_models.h): "native" (our TFLite reader + XNNPACK, in this
// process; the default) or "wasm" (TFLite's WebAssembly runtime in a Node
// process; the reference, and the fallback when the native one cannot
// load). The pre- and post-processing here is the same for both: the palm
// detector's anchors and weighted non-maximum suppression, the rotated
// hand crop, keypoints back to the frame, tracking a hand from its last
// keypoints; the numbers are MediaPipe's published graph options. The
// models come from the npm package @mediapipe/hands that scripts/setup.sh
// installs into NpmDir() (core/data_dirs.h); nothing is downloaded.
//
// Contract: Detect() sends one frame and waits for its hands; hands are
// tracked from one call to the next (the next frame is searched around the
// last keypoints first; the palm detector looks for the others, see
// HandLandmarkerOptions::palm_every; a palm where a tracked hand already is
// gets no landmark run, as in MediaPipe), Reset() forgets them. Keypoint order is
// MediaPipe's (= OpenPose-21): 0 wrist, 1-4 thumb, 5-8 index, 9-12 middle,
// 13-16 ring, 17-20 little finger, tips at 4, 8, 12, 16, 20.
#pragma once

#include <array>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/hand_keypoints.h"

namespace doasido::filters {

struct LandmarkedHand {
  double score = 0;  // hand presence, 0..1
  // The model's probability of a right hand as seen in a mirror (MediaPipe
  // assumes selfie input): for camera footage, 1 - right is the right hand.
  double right = 0;
  cv::Rect2d box;  // of the keypoints, pixels of the frame passed in
  std::array<cv::Point3d, kHandKeypoints> keypoints;  // pixels; z relative to the wrist
  std::array<cv::Point3d, kHandKeypoints> world;      // metres about the hand's centre
};

struct HandLandmarkerOptions {
  int max_hands = 2;
  // Frames are shrunk so that their longer side is at most this before they
  // are sent (the palm detector sees 192 x 192, the landmark model a 224 x
  // 224 crop; 640 keeps a hand of a tenth of the frame at full detail).
  int max_side = 640;
  std::string clip;  // for error messages
  // Which runtime runs the models: "native" or "wasm" (kBackendNative,
  // kBackendWasm in filters/hand_models.h).
  std::string backend = "native";
  // Which models: "full", "lite" or "lite_landmark" (filters/hand_models.h).
  std::string models = "full";
  // MediaPipe's VIDEO mode runs the palm detector on every frame where
  // fewer than max_hands hands are tracked. Here, while at least one hand is
  // tracked, it runs on every palm_every-th frame only (1: every frame, as
  // MediaPipe), except that with no hand tracked it runs on every frame, and
  // when a tracked hand's presence drops below 0.5 it runs on that frame and
  // the next lost_search - 1 (fewer when max_hands hands are tracked again).
  int palm_every = 1;
  int lost_search = 1;
  // A tracked hand whose crop (the landmark model's input, sampled where
  // the model last ran on that hand) changed on at most this fraction of
  // its pixels, by more than unchanged_crop_level gray levels in some
  // channel, since that run keeps that run's keypoints without running the
  // model again. Compared with the last run, not the last frame, so slow
  // motion adds up until it counts. 0: the model runs on every tracked hand.
  double unchanged_crop_fraction = 0;
  int unchanged_crop_level = 15;  // the activity signal's pixel_threshold
  // The wide search (WideSearch below) on video: on the first frame after
  // Reset() when no hand is tracked there, and on every wide_every-th frame
  // after it with no hand tracked. 0: only DetectStill() searches wide.
  int wide_every = 0;
  // On video, the wide search also runs on this many frames from the one
  // where a tracked hand is lost (while fewer than max_hands are tracked):
  // a hand moving fast, blurred or half hidden by what it carries, that
  // neither its last crop nor the palm detector on the whole frame finds
  // again (02_cups 286-296: a cup lifted to the frame's top). 0: never.
  int lost_wide = 0;
};

// What the wide search looks at beyond the palm detector on the whole
// frame letterboxed (issue 54: hands that palm detector misses, a hand
// filling the frame, small hands, grayscale and low-contrast input):
//   - the palm detector on overlapping zoomed windows (side: half the
//     frame's longer side, at most its shorter one; half a window apart);
//   - the landmark model straight on the whole frame (letterboxed, and its
//     centred square) at four rotations, with no palm at all;
//   - where a crop is low in contrast (its 2nd to 98th percentile of
//     brightness spans less than kLowContrast), the same crop stretched to
//     that range, as one more candidate.
// A candidate is a hand when the landmark model's presence on it is at
// least 0.5, and again on the crop its own keypoints give (the crop the
// tracker would use next): that second run's keypoints are kept. Its side
// is the landmark model's handedness, as for every hand.
inline constexpr double kLowContrast = 0.5;

// A square crop of the frame, rotated: where the landmark model looks.
struct HandCrop {
  double cx = 0, cy = 0;  // centre, pixels of the (shrunk) frame
  double side = 0;        // pixels
  double rotation = 0;    // radians; the crop's up is the hand's up
};

// A hand followed from one frame to the next: where to look next, and
// its last landmark run (the crop it ran on, that crop's input tensor, and
// what it found, in the shrunk frame's pixels).
struct TrackedHand {
  HandCrop next;
  HandCrop run_crop;
  std::vector<float> run_input;
  LandmarkedHand run_hand;
};

// A palm the palm detector found (after non-maximum suppression).
struct DetectedPalm {
  double score = 0;
  cv::Rect2d box;                        // pixels of the frame passed in
  std::array<cv::Point2d, 7> keypoints;  // 0 wrist, 2 middle finger's base, ...
};

class HandModels;

class HandLandmarker {
 public:
  // Loads the models on the runtime asked for (the wasm one when the native
  // one cannot load; note() says why). Throws Error("hand_detector_unavailable")
  // saying what is missing (the npm packages, node) and how to install it.
  explicit HandLandmarker(HandLandmarkerOptions options = {});
  ~HandLandmarker();
  HandLandmarker(const HandLandmarker&) = delete;
  HandLandmarker& operator=(const HandLandmarker&) = delete;

  // Hands in a BGR frame, boxes and keypoints in its pixels. Throws
  // Error("hand_detector_failed") when the process dies or answers garbage.
  std::vector<LandmarkedHand> Detect(const cv::Mat& bgr);
  // One still image: Reset(), then Detect() with the wide search. A gray
  // (one channel) or BGRA image is taken too.
  std::vector<LandmarkedHand> DetectStill(const cv::Mat& image);
  void Reset();
  // True when a hand of the last frame is tracked into the next (else
  // Detect runs the palm detector; PalmGate in filters/learned_hand_detector.h
  // decides whether to call it at all).
  bool tracking() const { return !tracked_.empty(); }
  // The palm detector alone on a BGR frame (no tracking, no landmarks).
  std::vector<DetectedPalm> DetectPalms(const cv::Mat& bgr);
  // CPU milliseconds the models took on the last frame (in the runtime).
  double last_ms() const { return last_ms_; }
  // Landmark runs saved by unchanged crops since the landmarker was made.
  int reused() const { return reused_; }
  // Wide searches run since the landmarker was made, and the hands they
  // added (beyond the palm detector's on the whole frame).
  int wide_searches() const { return wide_searches_; }
  int wide_found() const { return wide_found_; }
  // The runtime that runs the models ("native" or "wasm"), and why it is
  // not the one asked for (empty when it is).
  const char* backend() const;
  const std::string& note() const { return note_; }

 private:
  cv::Mat Rgb(const cv::Mat& bgr, double* shrink) const;
  std::vector<DetectedPalm> Palms(const cv::Mat& rgb);
  bool Landmarks(const cv::Mat& rgb, const HandCrop& crop, LandmarkedHand* hand,
                 bool stretch = false);
  bool CropUnchanged(const cv::Mat& rgb, const TrackedHand& track);
  std::vector<TrackedHand> WideSearch(const cv::Mat& rgb, const std::vector<LandmarkedHand>& known);
  bool WideDue();
  std::vector<LandmarkedHand> DetectRgb(const cv::Mat& rgb, double shrink, bool wide);

  HandLandmarkerOptions options_;
  std::unique_ptr<HandModels> models_;
  std::string note_;
  std::vector<cv::Point2d> anchors_;
  std::vector<TrackedHand> tracked_;  // where to look first in the next frame
  int since_palms_ = 0;            // frames since the palm detector last ran
  int searching_ = 0;              // frames left to look for a lost hand on every frame
  int lost_wide_left_ = 0;         // frames left of the wide search after a loss
  int frames_ = 0;                 // frames since Reset()
  int handless_ = 0;               // frames without a tracked hand since the last wide search
  int wide_searches_ = 0, wide_found_ = 0;
  std::vector<float> input_, compare_;
  double last_ms_ = 0;
  int reused_ = 0;
};

// True when the models can run on some runtime (the model files for the
// native one; node and the npm packages for the wasm one). Tests and the
// bench use it to say why they skip.
bool HandLandmarkerAvailable(std::string* why = nullptr);

}  // namespace doasido::filters
