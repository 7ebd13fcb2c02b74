// Objectron's two stages on a sequence of frames, tracked as MediaPipe's
// graph does (objectron_cpu.pbtxt, box_landmark_cpu.pbtxt): the 2D detector
// (objects/box_detector.h) finds boxes of the configured categories; each
// new box gets a track whose category, and so box-landmark model, never
// changes; the landmark model looks at a square crop of the box enlarged
// 1.5 times, and in the next frame at the same crop made from this frame's
// keypoints (their extent, turned so that the box's up is the crop's up).
// A track ends where the presence drops below its threshold. The detector
// runs on the frame a track is lost, every idle_detect_every-th frame while
// nothing is tracked and every detect_every-th frame otherwise
// (BoxKeypointsConfig); a detection where a track already is is that track.
//
// Contract: Track() takes frames in order and returns the objects of each,
// keypoints in pixels of the frame passed in times `scale` (0 at the
// top-left corner of the top-left pixel); Reset() forgets the tracks.
// Throws Error("object_detector_unavailable") at construction when the
// models cannot load, Error("object_detector_failed") when a run fails.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "objects/box_detector.h"
#include "objects/box_follower.h"
#include "objects/box_keypoints.h"
#include "objects/box_keypoints_config.h"
#include "objects/hand_proposals.h"
#include "objects/objectron_models.h"

namespace doasido::objects {

// A square crop of the frame, turned: where a box-landmark model looks.
struct BoxCrop {
  double cx = 0, cy = 0;  // centre, pixels
  double side = 0;        // pixels
  double rotation = 0;    // radians, clockwise on screen; the crop's up is the box's up
};

// The crop of a box of `w` x `h` pixels about (cx, cy): enlarged `scale`
// times and squared on its long side (RectTransformationCalculator's
// scale_x = scale_y = scale, square_long).
BoxCrop CropFromBox(double cx, double cy, double w, double h, double rotation, double scale);
// The unturned crop of a box on screen (a detection, a proposal, a person's
// prompt or the follower's box): CropFromBox about the box's centre.
BoxCrop CropAroundBox(const cv::Rect2d& box, double scale);
// The next frame's crop from this frame's keypoints: their extent on screen,
// turned by the angle that makes the box's projected up axis (bottom-face
// centre to top-face centre) point up; unturned when that axis is shorter
// than a tenth of the extent (a box seen from above).
BoxCrop CropFromKeypoints(const std::array<Eigen::Vector2d, kBoxKeypoints>& keypoints, double scale);
// The affine map from the crop's 224 x 224 pixels (continuous, 0 at the
// corner) to the frame's.
cv::Matx23d CropToFrame(const BoxCrop& crop);
// The landmark model's input for `crop` of an RGB frame of 8-bit pixels:
// 224 x 224 x 3 floats in [0, 1], bilinear, the frame's border replicated
// (box_landmark_cpu.pbtxt's BORDER_REPLICATE).
void LandmarkInput(const cv::Mat& rgb, const BoxCrop& crop, std::vector<float>* out);

// An object shown by hand on one frame (BoxTracker::Seed).
struct SeedBox {
  std::int64_t frame = 0;        // the file's frame index (0 for an image)
  std::string category = "cup";
  cv::Rect2d box;                // pixels of the input as displayed
};

class BoxTracker {
 public:
  BoxTracker(BoxKeypointsConfig config, std::string clip);
  std::vector<ObjectObservation> Track(const cv::Mat& bgr, int frame, double scale = 1.0);
  // An object shown by hand (or by another detector): `box` holds one
  // object of `category`, in the pixels Track() reports (the frame's times
  // its scale). The next Track() starts a prompted track there, unless a
  // track is there already: for objects the 2D detector misses, such as
  // 02_cups' red plastic cups. A prompted track follows the box in 2D
  // (objects/box_follower.h), the box-landmark model looking at that box
  // each frame; the track ends where the model's keypoints leave the box
  // (BoxKeypointsConfig's prompt_ fields).
  void Seed(const std::string& category, const cv::Rect2d& box);
  // CPU milliseconds in the prompted tracks' 2D follower, and its runs.
  double follower_ms() const { return follower_ms_; }
  int follower_runs() const { return follower_runs_; }
  // The hands of the next Track()'s frame (keypoints in the pixels Track()
  // reports). With hand_proposals on, every hand_proposal_every-th frame
  // (and the first) each hand whose grasp point lies in no tracked object
  // has boxes beside its fingers tried (objects/hand_proposals.h) with every
  // loaded category's model; the most present box at or above min_presence
  // starts a track.
  void NearHands(std::vector<HandPoints2d> hands);
  void Reset();
  const ObjectronModels& models() const { return *models_; }

 private:
  struct Tracked {
    int id = 0;
    std::string category;
    BoxCrop next;
    cv::Rect2d extent;  // of the keypoints, pixels of the (shrunk) frame
    std::unique_ptr<BoxFollower> follower;  // a prompted track's 2D follower, else null
    int missing = 0;                // a prompted track's frames in a row without keypoints
    Eigen::Vector2d seen_at{NAN, NAN};  // a prompted track's last keypoint centre, pixels of the (shrunk) frame
  };
  // True when max_objects are tracked or a kept track is at `box` already.
  bool NoRoomFor(const cv::Rect2d& box, const std::vector<Tracked>& kept) const;
  // A prompted track's next frame: the follower's box, the model's keypoints
  // on it when present. False when the track ends.
  bool FollowPrompted(const cv::Mat& rgb, int frame, Tracked* t, std::vector<ObjectObservation>* found);
  void StartPrompted(const cv::Mat& rgb, int frame, const std::string& category, const cv::Rect2d& box,
                     std::vector<Tracked>* kept, std::vector<ObjectObservation>* found);
  // Runs `category`'s model on `crop`; false when the box is not present.
  bool Landmarks(const cv::Mat& rgb, const std::string& category, const BoxCrop& crop,
                 ObjectObservation* seen);
  void DetectNew(const cv::Mat& rgb, int frame, std::vector<Tracked>* kept,
                 std::vector<ObjectObservation>* found);
  // Starts a track of `category` at `box` (pixels of `rgb`) unless a kept
  // track is there already or the model sees no box.
  void StartTrack(const cv::Mat& rgb, int frame, const std::string& category, const cv::Rect2d& box,
                  std::vector<Tracked>* kept, std::vector<ObjectObservation>* found);

  // Tries the boxes beside each of hands_ (pixels of `rgb`).
  void ProposeNearHands(const cv::Mat& rgb, int frame, std::vector<Tracked>* kept,
                        std::vector<ObjectObservation>* found);
  // Starts a track from an observation the model already made on a crop,
  // as track `id` (< 0: a new one).
  void Adopt(ObjectObservation seen, std::vector<Tracked>* kept, std::vector<ObjectObservation>* found,
             int id = -1);
  // The lost track a box beside a hand continues (hand_rejoin_frames), or -1.
  int Rejoin(const ObjectObservation& seen);

  BoxKeypointsConfig config_;
  std::string clip_;
  std::unique_ptr<ObjectronModels> models_;
  std::vector<Tracked> tracks_;
  std::vector<std::pair<std::string, cv::Rect2d>> seeds_;  // for the next Track()
  int next_id_ = 0;
  int since_detection_ = -1;  // frames since the detector ran; -1: not yet (it runs first)
  std::vector<HandPoints2d> hands_;  // for the next Track(), pixels of the (shrunk) frame
  int since_proposals_ = -1;         // frames since boxes were tried beside hands; -1: not yet
  struct Lost {
    int id = 0;
    std::string category;
    cv::Rect2d extent;  // its last box, pixels of the (shrunk) frame
    int frame = 0;
  };
  std::vector<Lost> lost_;  // tracks lost within hand_rejoin_frames
  std::vector<float> input_;
  double follower_ms_ = 0;
  int follower_runs_ = 0;
};

}  // namespace doasido::objects
