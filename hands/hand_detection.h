// Runs the hand models (filters::HandLandmarker: palm detector where no
// hand is tracked, landmark model on a crop around the previous frame's
// keypoints elsewhere) on every frame of a video span or on one image, and
// returns each frame's hands in pixels of the input as displayed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "filters/hand_landmarker.h"
#include "hands/hand_observation.h"
#include "video/video_decoder.h"

namespace doasido::hands {

struct DetectedFrames {
  std::vector<FrameObservations> frames;
  int width = 0, height = 0;     // the input as displayed
  double fps = 0;                // 0 for an image
  std::int64_t first_frame = 0;  // file frame of frames[0]
  double model_seconds = 0;      // inside the models (their own clock)
  double seconds = 0;            // wall clock: decoding, resizing and the models
};

// Every frame of `span` (first/last frame or seconds, DecoderOptions) of
// `video`. Frames are decoded at most `max_side` pixels on their longer side
// (the models see no more than 640 anyway). `progress` (may be empty) gets
// the number of frames done after each frame. Throws the decoder's errors
// (video_open_failed, video_truncated, naming the file) and the
// landmarker's.
DetectedFrames DetectVideo(const std::filesystem::path& video, DecoderOptions span,
                           int max_side, filters::HandLandmarker& landmarker,
                           const std::function<void(std::int64_t)>& progress = {});

// One still image (BGR, gray or BGRA), as one frame: the landmarker is
// reset and searches wide (filters::HandLandmarker::DetectStill).
DetectedFrames DetectImage(const cv::Mat& bgr, filters::HandLandmarker& landmarker);

}  // namespace doasido::hands
