// The box keypoints of every frame of a video, or of one still image
// (objects/box_tracker.h), with what the models cost.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <vector>

#include <opencv2/core.hpp>

#include "objects/box_tracker.h"
#include "video/video_decoder.h"

namespace doasido::objects {

struct DetectedObjects {
  std::vector<std::vector<ObjectObservation>> frames;  // one entry per frame, in order
  int width = 0, height = 0;     // the input as displayed
  double fps = 0;                // 0 for an image
  std::int64_t first_frame = 0;  // file frame of frames[0]
  double detector_ms = 0, landmark_ms = 0;  // CPU time inside the models
  int detector_runs = 0, landmark_runs = 0;
  double seconds = 0;  // wall clock: decoding, resizing and the models
};

// Hands per file frame, keypoints in pixels of the input as displayed (the
// hands stage's or the hand landmarker's): where the tracker also looks for
// objects (BoxTracker::NearHands).
using HandsByFrame = std::map<std::int64_t, std::vector<HandPoints2d>>;

// Every frame of `span` (DecoderOptions) of `video`, decoded at most
// max_side pixels on the longer side (the tracker's config). An
// observation's `frame` is the file's frame index. `progress` (may be
// empty) gets the number of frames done; `seeds` start tracks on their
// frames (BoxTracker::Seed); `hands` (may be null) the hands of each frame.
// Throws the decoder's errors.
DetectedObjects ObjectsInVideo(const std::filesystem::path& video, DecoderOptions span,
                               int max_side, BoxTracker& tracker,
                               const std::function<void(std::int64_t)>& progress = {},
                               const std::vector<SeedBox>& seeds = {},
                               const HandsByFrame* hands = nullptr);

// One still image (BGR) as frame 0; the tracker is reset first; `hands`
// (may be null) its hands under frame 0.
DetectedObjects ObjectsInImage(const cv::Mat& bgr, BoxTracker& tracker,
                               const std::vector<SeedBox>& seeds = {},
                               const HandsByFrame* hands = nullptr);

}  // namespace doasido::objects
