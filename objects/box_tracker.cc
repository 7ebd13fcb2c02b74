#include "objects/box_tracker.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "core/clock.h"
#include "core/error.h"

namespace doasido::objects {

namespace {

// Corners 1-8 whose index - 1 has bit 1 set are on the top face.
bool TopCorner(int k) { return ((k - 1) & 2) != 0; }

// Two tracks whose keypoint extents overlap this much are one object.
constexpr double kSameTrackIou = 0.5;
// A box's up axis shorter than this fraction of its extent gives no angle.
constexpr double kMinUpAxis = 0.1;

cv::Rect2d Extent(const std::array<Eigen::Vector2d, kBoxKeypoints>& p) {
  double x1 = INFINITY, y1 = INFINITY, x2 = -INFINITY, y2 = -INFINITY;
  for (const Eigen::Vector2d& q : p) {
    x1 = std::min(x1, q.x());
    y1 = std::min(y1, q.y());
    x2 = std::max(x2, q.x());
    y2 = std::max(y2, q.y());
  }
  return {cv::Point2d(x1, y1), cv::Point2d(x2, y2)};
}

}  // namespace

BoxCrop CropFromBox(double cx, double cy, double w, double h, double rotation, double scale) {
  return {.cx = cx, .cy = cy, .side = std::max(w, h) * scale, .rotation = rotation};
}

BoxCrop CropAroundBox(const cv::Rect2d& box, double scale) {
  return CropFromBox(box.x + box.width / 2, box.y + box.height / 2, box.width, box.height, 0.0, scale);
}

BoxCrop CropFromKeypoints(const std::array<Eigen::Vector2d, kBoxKeypoints>& keypoints,
                          double scale) {
  Eigen::Vector2d top = Eigen::Vector2d::Zero(), bottom = Eigen::Vector2d::Zero();
  for (int k = 1; k < kBoxKeypoints; ++k) (TopCorner(k) ? top : bottom) += keypoints[k] / 4.0;
  const Eigen::Vector2d up = top - bottom;
  const cv::Rect2d e = Extent(keypoints);
  const double rotation =
      up.norm() >= kMinUpAxis * std::max(e.width, e.height) ? std::atan2(up.x(), -up.y()) : 0.0;
  return CropFromBox(e.x + e.width / 2, e.y + e.height / 2, e.width, e.height, rotation, scale);
}

cv::Matx23d CropToFrame(const BoxCrop& crop) {
  const double c = std::cos(crop.rotation), s = std::sin(crop.rotation);
  const double k = crop.side / kBoxInputSize;
  return {k * c, -k * s, crop.cx - crop.side / 2 * (c - s),
          k * s, k * c,  crop.cy - crop.side / 2 * (s + c)};
}

void LandmarkInput(const cv::Mat& rgb, const BoxCrop& crop, std::vector<float>* out) {
  // warpAffine works on pixel indices (centres at integers); the map is on
  // continuous coordinates (centres at +0.5).
  const cv::Matx23d m = CropToFrame(crop);
  const cv::Matx23d idx(m(0, 0), m(0, 1), m(0, 2) + 0.5 * (m(0, 0) + m(0, 1)) - 0.5,
                        m(1, 0), m(1, 1), m(1, 2) + 0.5 * (m(1, 0) + m(1, 1)) - 0.5);
  cv::Mat patch;
  cv::warpAffine(rgb, patch, cv::Mat(idx), cv::Size(kBoxInputSize, kBoxInputSize),
                 cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
  out->resize(static_cast<std::size_t>(kBoxInputSize) * kBoxInputSize * 3);
  cv::Mat as_float(kBoxInputSize, kBoxInputSize, CV_32FC3, out->data());
  patch.convertTo(as_float, CV_32FC3, 1.0 / 255.0);
}

BoxTracker::BoxTracker(BoxKeypointsConfig config, std::string clip)
    : config_(std::move(config)), clip_(std::move(clip)),
      models_(std::make_unique<ObjectronModels>(config_.categories, clip_)) {}

void BoxTracker::Reset() {
  tracks_.clear();
  seeds_.clear();
  hands_.clear();
  lost_.clear();
  since_detection_ = -1;
  since_proposals_ = -1;
}

void BoxTracker::NearHands(std::vector<HandPoints2d> hands) { hands_ = std::move(hands); }

void BoxTracker::Adopt(ObjectObservation seen, std::vector<Tracked>* kept,
                       std::vector<ObjectObservation>* found, int id) {
  seen.track = id >= 0 ? id : next_id_++;
  kept->push_back({seen.track, seen.category, CropFromKeypoints(seen.keypoints_2d, config_.crop_scale),
                   Extent(seen.keypoints_2d)});
  found->push_back(seen);
}

int BoxTracker::Rejoin(const ObjectObservation& seen) {
  const cv::Rect2d e = Extent(seen.keypoints_2d);
  const cv::Point2d c(e.x + e.width / 2, e.y + e.height / 2);
  for (auto it = lost_.begin(); it != lost_.end(); ++it) {
    const cv::Rect2d near(it->extent.x - it->extent.width / 2, it->extent.y - it->extent.height / 2,
                          2 * it->extent.width, 2 * it->extent.height);
    if (it->category != seen.category || seen.frame - it->frame > config_.hand_rejoin_frames ||
        !near.contains(c)) {
      continue;
    }
    const int id = it->id;
    lost_.erase(it);
    return id;
  }
  return -1;
}

void BoxTracker::ProposeNearHands(const cv::Mat& rgb, int frame, std::vector<Tracked>* kept,
                                  std::vector<ObjectObservation>* found) {
  const HandProposalConfig proposal{.sizes = config_.hand_proposal_sizes,
                                    .offset = config_.hand_proposal_offset};
  for (const HandPoints2d& hand : hands_) {
    if (static_cast<int>(kept->size()) >= config_.max_objects) return;
    const Eigen::Vector2d grasp = (hand[4] + hand[8] + hand[12]) / 3.0;
    bool held = false;  // the hand's object is tracked already
    for (const Tracked& t : *kept) held |= t.extent.contains(cv::Point2d(grasp.x(), grasp.y()));
    if (held) continue;
    ObjectObservation best{.frame = frame};
    for (const cv::Rect2d& box : HandProposals(hand, proposal)) {
      const BoxCrop crop = CropAroundBox(box, config_.crop_scale);
      for (const std::string& category : config_.categories) {
        ObjectObservation seen{.frame = frame};
        if (Landmarks(rgb, category, crop, &seen) && seen.score > best.score) best = seen;
      }
    }
    if (best.score <= 0) continue;
    // The model's box on a guessed crop is rough; on the crop its own
    // keypoints give (the one tracking would use next) it is as on a
    // tracked frame, so that second reading is kept when it holds.
    ObjectObservation again{.frame = frame};
    if (Landmarks(rgb, best.category, CropFromKeypoints(best.keypoints_2d, config_.crop_scale), &again)) {
      best = again;
    }
    bool duplicate = false;
    for (const Tracked& t : *kept) duplicate |= BoxIoU(t.extent, Extent(best.keypoints_2d)) > config_.same_object_iou;
    if (!duplicate) Adopt(best, kept, found, Rejoin(best));
  }
}

bool BoxTracker::Landmarks(const cv::Mat& rgb, const std::string& category, const BoxCrop& crop,
                           ObjectObservation* seen) {
  LandmarkInput(rgb, crop, &input_);
  BoxLandmarkOutput out;
  models_->Landmarks(category, input_.data(), &out);
  if (!(out.presence >= config_.min_presence)) return false;
  const cv::Matx23d m = CropToFrame(crop);
  for (int k = 0; k < kBoxKeypoints; ++k) {
    const double u = out.keypoints[2 * k], v = out.keypoints[2 * k + 1];
    seen->keypoints_2d[k] = {m(0, 0) * u + m(0, 1) * v + m(0, 2), m(1, 0) * u + m(1, 1) * v + m(1, 2)};
  }
  seen->category = category;
  seen->score = out.presence;
  return true;
}

void BoxTracker::DetectNew(const cv::Mat& rgb, int frame, std::vector<Tracked>* kept,
                           std::vector<ObjectObservation>* found) {
  std::vector<float> input;
  DetectorInput(rgb, &input);
  DetectorOutput out;
  models_->Detect(input.data(), &out);
  const std::vector<DetectedBox> boxes =
      DecodeDetections(out, models_->labels(), config_.categories, config_.min_detection_score,
                       config_.nms_iou, config_.max_objects);
  for (const DetectedBox& b : boxes) {
    const cv::Rect2d box(b.box.x * rgb.cols, b.box.y * rgb.rows, b.box.width * rgb.cols,
                         b.box.height * rgb.rows);
    StartTrack(rgb, frame, b.category, box, kept, found);
  }
}

bool BoxTracker::NoRoomFor(const cv::Rect2d& box, const std::vector<Tracked>& kept) const {
  if (static_cast<int>(kept.size()) >= config_.max_objects) return true;
  for (const Tracked& t : kept) {
    if (BoxIoU(t.extent, box) > config_.same_object_iou) return true;
  }
  return false;
}

void BoxTracker::StartTrack(const cv::Mat& rgb, int frame, const std::string& category,
                            const cv::Rect2d& box, std::vector<Tracked>* kept,
                            std::vector<ObjectObservation>* found) {
  if (NoRoomFor(box, *kept)) return;
  const BoxCrop crop = CropAroundBox(box, config_.crop_scale);
  ObjectObservation seen{.frame = frame};
  if (Landmarks(rgb, category, crop, &seen)) Adopt(seen, kept, found);
}

void BoxTracker::StartPrompted(const cv::Mat& rgb, int frame, const std::string& category,
                               const cv::Rect2d& box, std::vector<Tracked>* kept,
                               std::vector<ObjectObservation>* found) {
  if (NoRoomFor(box, *kept)) return;
  const cv::Rect whole(0, 0, rgb.cols, rgb.rows);
  const cv::Rect start = cv::Rect(box) & whole;
  if (start.width < 2 || start.height < 2) return;  // the box is off the frame
  Tracked t{.id = next_id_++, .category = category, .extent = start};
  t.follower = std::make_unique<BoxFollower>(BoxFollowerConfig{.side = config_.prompt_follow_side,
                                                               .grid = config_.prompt_follow_grid,
                                                               .max_error = config_.prompt_follow_max_error,
                                                               .min_points = config_.prompt_follow_min_points});
  t.follower->Start(rgb, start);
  ObjectObservation seen{.frame = frame, .track = t.id};
  const BoxCrop crop = CropAroundBox(start, config_.crop_scale);
  if (Landmarks(rgb, category, crop, &seen)) {
    t.seen_at = seen.keypoints_2d[0];
    found->push_back(seen);
  } else {
    t.missing = 1;
  }
  kept->push_back(std::move(t));
}

bool BoxTracker::FollowPrompted(const cv::Mat& rgb, int frame, Tracked* t,
                                std::vector<ObjectObservation>* found) {
  const double start = ThreadCpuMs();
  const bool followed = t->follower->Follow(rgb);
  follower_ms_ += ThreadCpuMs() - start;
  ++follower_runs_;
  if (!followed) return false;
  const cv::Rect2d box = t->follower->box();
  t->extent = box;
  ObjectObservation seen{.frame = frame, .track = t->id};
  if (Landmarks(rgb, t->category, CropAroundBox(box, config_.crop_scale), &seen)) {
    // The model sees a box of the category in the crop, but not where the
    // follower put the object: one of them is on something else (a
    // look-alike beside it, the hand), so the track ends rather than risk
    // following the wrong object.
    // After frames unseen the follower has drifted unchecked (onto the
    // hand that hid the object, say): the keypoints must also be back
    // where the object was last seen.
    const Eigen::Vector2d centre(box.x + box.width / 2, box.y + box.height / 2);
    const Eigen::Vector2d& at = seen.keypoints_2d[0];
    const double reach = config_.prompt_max_jump * std::max(box.width, box.height);
    if ((at - centre).norm() > reach || (!std::isnan(t->seen_at.x()) && (at - t->seen_at).norm() > reach)) {
      return false;
    }
    t->seen_at = at;
    found->push_back(seen);
    t->missing = 0;
    return true;
  }
  return ++t->missing <= config_.prompt_max_missing_frames;
}

void BoxTracker::Seed(const std::string& category, const cv::Rect2d& box) {
  CategoryNamed(category);
  if (std::find(config_.categories.begin(), config_.categories.end(), category) ==
      config_.categories.end()) {
    throw Error("bad_arguments", "a seed of category " + category + ", whose model is not loaded",
                {.clip = clip_, .field = "categories"});
  }
  seeds_.emplace_back(category, box);
}

std::vector<ObjectObservation> BoxTracker::Track(const cv::Mat& bgr, int frame, double scale) {
  if (bgr.empty() || bgr.type() != CV_8UC3) {
    throw Error(kObjectDetectorFailed, "the object models need a BGR frame of 8-bit pixels",
                {.clip = clip_});
  }
  const double shrink =
      std::min(1.0, static_cast<double>(config_.max_side) / std::max(bgr.cols, bgr.rows));
  cv::Mat rgb;
  if (shrink < 1.0) {
    cv::Mat small;
    cv::resize(bgr, small, {}, shrink, shrink, cv::INTER_AREA);
    cv::cvtColor(small, rgb, cv::COLOR_BGR2RGB);
  } else {
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  }
  std::erase_if(lost_, [&](const Lost& l) { return frame - l.frame > config_.hand_rejoin_frames; });
  std::vector<ObjectObservation> found;
  std::vector<Tracked> kept;
  bool lost = false;
  for (Tracked& t : tracks_) {
    if (t.follower) {
      if (FollowPrompted(rgb, frame, &t, &found)) {
        kept.push_back(std::move(t));
      } else {
        lost = true;
      }
      continue;
    }
    ObjectObservation seen{.frame = frame, .track = t.id};
    if (!Landmarks(rgb, t.category, t.next, &seen)) {
      lost = true;
      lost_.push_back({t.id, t.category, t.extent, frame});
      continue;
    }
    const cv::Rect2d extent = Extent(seen.keypoints_2d);
    bool duplicate = false;  // two tracks drifted onto one object: the older stays
    for (const Tracked& k : kept) duplicate |= BoxIoU(k.extent, extent) > kSameTrackIou;
    if (duplicate) continue;
    kept.push_back({t.id, t.category, CropFromKeypoints(seen.keypoints_2d, config_.crop_scale), extent});
    found.push_back(seen);
  }
  const double to_input = scale / shrink;
  for (const auto& [category, box] : seeds_) {
    StartPrompted(rgb, frame, category,
               cv::Rect2d(box.x / to_input, box.y / to_input, box.width / to_input, box.height / to_input),
               &kept, &found);
  }
  seeds_.clear();
  if (config_.hand_proposals && !hands_.empty()) {
    if (since_proposals_ < 0 || since_proposals_ + 1 >= config_.hand_proposal_every) {
      since_proposals_ = 0;
      for (HandPoints2d& hand : hands_) {
        for (Eigen::Vector2d& p : hand) p /= to_input;
      }
      ProposeNearHands(rgb, frame, &kept, &found);
    } else {
      ++since_proposals_;
    }
  }
  hands_.clear();
  const int every = kept.empty() ? config_.idle_detect_every : config_.detect_every;
  const bool due = lost || since_detection_ < 0 || since_detection_ + 1 >= every;
  if (due && static_cast<int>(kept.size()) < config_.max_objects) {
    since_detection_ = 0;
    DetectNew(rgb, frame, &kept, &found);
  } else {
    ++since_detection_;
  }
  tracks_ = std::move(kept);
  for (ObjectObservation& o : found) {
    for (Eigen::Vector2d& p : o.keypoints_2d) p *= to_input;
  }
  return found;
}

}  // namespace doasido::objects
