// The learned hand detector: MediaPipe Hands (palm detector + 21-keypoint
// landmark model) in a long-lived Node process running
// filters/mediapipe_hands.js on TFLite's WebAssembly runtime, one thread.
// The models and the runtime come from npm packages that scripts/setup.sh
// installs into NpmDir() (core/data_dirs.h); nothing is downloaded at run
// time. About 50-90 ms per frame without hands and 35-50 ms more per hand
// on one core here, so callers sample a few frames per second.
//
// Contract: Detect() sends one frame and waits for its hands; hands are
// tracked from one call to the next (the next frame is searched around the
// last keypoints first), Reset() forgets them. Keypoint order is
// MediaPipe's (= OpenPose-21): 0 wrist, 1-4 thumb, 5-8 index, 9-12 middle,
// 13-16 ring, 17-20 little finger, tips at 4, 8, 12, 16, 20.
#pragma once

#include <sys/types.h>

#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace doasido::filters {

inline constexpr int kHandKeypoints = 21;
inline constexpr int kFingertips[5] = {4, 8, 12, 16, 20};

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
  std::string node = "node";
  std::string clip;  // for error messages
};

class HandLandmarker {
 public:
  // Starts Node and loads the models. Throws Error("hand_detector_unavailable")
  // saying what is missing (node, the npm packages) and how to install it.
  explicit HandLandmarker(HandLandmarkerOptions options = {});
  ~HandLandmarker();
  HandLandmarker(const HandLandmarker&) = delete;
  HandLandmarker& operator=(const HandLandmarker&) = delete;

  // Hands in a BGR frame, boxes and keypoints in its pixels. Throws
  // Error("hand_detector_failed") when the process dies or answers garbage.
  std::vector<LandmarkedHand> Detect(const cv::Mat& bgr);
  void Reset();
  // Milliseconds the models took on the last frame (inside Node).
  double last_ms() const { return last_ms_; }

 private:
  std::string ReadLine();
  void WriteAll(const void* data, size_t size);

  HandLandmarkerOptions options_;
  pid_t pid_ = -1;
  int to_child_ = -1, from_child_ = -1;
  std::string buffered_;
  double last_ms_ = 0;
  std::int64_t next_id_ = 0;
};

// True when node and the npm packages are installed (tests and the bench
// use it to say why they skip).
bool HandLandmarkerAvailable(std::string* why = nullptr);

}  // namespace doasido::filters
