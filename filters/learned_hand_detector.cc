#include "filters/learned_hand_detector.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "filters/out_of_frame.h"

namespace doasido::filters {
namespace {

// The 21-keypoint skeleton's bones, palm edges included.
constexpr int kBones[][2] = {{0, 1},   {1, 2},   {2, 3},   {3, 4},   {0, 5},   {5, 6},
                             {6, 7},   {7, 8},   {0, 9},   {9, 10},  {10, 11}, {11, 12},
                             {0, 13},  {13, 14}, {14, 15}, {15, 16}, {0, 17},  {17, 18},
                             {18, 19}, {19, 20}, {5, 9},   {9, 13},  {13, 17}, {1, 5}};

cv::Point2d At(const LandmarkedHand& hand, int k) { return {hand.keypoints[k].x, hand.keypoints[k].y}; }

double Round(double v, double unit) { return std::round(v / unit) * unit; }

Json PointsJson(const std::array<cv::Point3d, kHandKeypoints>& points, double scale, double unit) {
  Json out = Json::array();
  for (const cv::Point3d& p : points) {
    out.push_back({Round(p.x * scale, unit), Round(p.y * scale, unit), Round(p.z * scale, unit)});
  }
  return out;
}

}  // namespace

FingertipEvidence ObjectEdgesAtFingertips(const cv::Mat& gray, const LandmarkedHand& hand,
                                          const LearnedDetectorConfig& config) {
  const double palm = cv::norm(At(hand, 0) - At(hand, 9));
  if (!(palm > 1.0)) return {};
  const int reach = std::max(2, static_cast<int>(std::lround(config.fingertip_reach * palm)));
  cv::Rect roi(cv::Point(static_cast<int>(hand.box.x) - reach, static_cast<int>(hand.box.y) - reach),
               cv::Point(static_cast<int>(hand.box.br().x) + reach + 1,
                         static_cast<int>(hand.box.br().y) + reach + 1));
  roi &= cv::Rect(0, 0, gray.cols, gray.rows);
  if (roi.area() == 0) return {};
  const cv::Point2d origin(roi.x, roi.y);
  cv::Mat hand_mask = cv::Mat::zeros(roi.size(), CV_8U), discs = hand_mask.clone();
  const int thickness = std::max(1, static_cast<int>(std::lround(config.hand_thickness * palm)));
  for (const auto& bone : kBones) {
    cv::line(hand_mask, At(hand, bone[0]) - origin, At(hand, bone[1]) - origin, 255, thickness,
             cv::LINE_8);
  }
  std::vector<cv::Point> palm_polygon;
  for (int k : {0, 1, 5, 9, 13, 17}) palm_polygon.push_back(At(hand, k) - origin);
  cv::fillConvexPoly(hand_mask, palm_polygon, 255);
  for (int tip : kFingertips) cv::circle(discs, At(hand, tip) - origin, reach, 255, cv::FILLED);
  const cv::Mat around = discs & ~hand_mask;
  const int area = cv::countNonZero(around);
  if (area < 4) return {};
  cv::Mat edges;
  cv::Canny(gray(roi), edges, 50, 150);
  const cv::Mat touched = edges & around;
  FingertipEvidence evidence;
  evidence.density = static_cast<double>(cv::countNonZero(touched)) / area;
  if (evidence.density > 0) {
    const cv::Rect box = cv::boundingRect(touched) + roi.tl();
    evidence.box = cv::Rect2d(box.x, box.y, box.width, box.height);
  }
  return evidence;
}

LearnedHandDetector::LearnedHandDetector(LearnedDetectorConfig config, const std::string& clip,
                                         ActivitySignalConfig activity)
    : config_(config),
      activity_(activity),
      landmarker_(HandLandmarkerOptions{.max_hands = config.max_hands,
                                        .clip = clip,
                                        .backend = config.backend,
                                        .models = config.models,
                                        .palm_every = config.palm_every}),
      palm_gate_(config.no_hand_palm_every, config.no_hand_changed_fraction, activity) {}

void PalmGate::Reset() {
  looked_.release();
  since_ = 0;
}

bool PalmGate::Look(const cv::Mat& gray) {
  ++since_;
  const bool look = looked_.empty() || gray.empty() || gray.size() != looked_.size() ||
                    (since_ >= every_ && (changed_fraction_ <= 0 ||
                                          MovingFraction(gray, looked_, {}, activity_) >=
                                              changed_fraction_));
  if (look) {
    gray.copyTo(looked_);
    since_ = 0;
  }
  return look;
}

std::int64_t SampleEvery(const VideoGeometry& geometry, const LearnedDetectorConfig& config) {
  const double fps = geometry.fps > 0 ? geometry.fps : 30.0;
  return std::max<std::int64_t>(1, std::llround(fps / config.sample_fps));
}

std::int64_t StillEvery(const VideoGeometry& geometry, const LearnedDetectorConfig& config) {
  const std::int64_t every = SampleEvery(geometry, config);
  if (config.still_sample_fps >= config.sample_fps) return every;
  const double fps = geometry.fps > 0 ? geometry.fps : 30.0;
  const std::int64_t samples = std::llround(fps / config.still_sample_fps / every);
  return every * std::max<std::int64_t>(1, samples);
}

void LearnedHandDetector::Begin(const VideoGeometry& geometry) {
  geometry_ = geometry;
  every_ = SampleEvery(geometry, config_);
  still_every_ = StillEvery(geometry, config_);
  seen_gray_.release();
  landmarker_.Reset();
  palm_gate_.Reset();
}

// Still: nothing moved around the hands of the last sample the models saw
// (or anywhere, when it had none), and that sample is recent enough.
bool LearnedHandDetector::Still(const FrameContext& context) const {
  if (still_every_ <= every_ || seen_gray_.empty() || context.gray.empty() ||
      context.gray.size() != seen_gray_.size() ||
      context.ordinal - seen_ordinal_ >= still_every_) {
    return false;
  }
  return MovingFraction(context.gray, seen_gray_, last_.hands, activity_) <=
         config_.still_changed_fraction;
}

void LearnedHandDetector::Consume(FrameContext& context) {
  if (context.ordinal % every_ != 0) {
    context.boxes = last_;
    return;
  }
  if (Still(context)) {
    // As if the models found what they found last time: those hands again,
    // and the ones held since then held one sample longer.
    samples_.push_back({{"frame", context.frame->index},
                        {"ms", 0.0},
                        {"held_from", seen_frame_},
                        {"hands", seen_hands_}});
    FrameBoxes found = seen_found_;
    std::vector<int> age(found.hands.size(), 0);
    for (Detection d : seen_detections_) {
      d.frame = context.frame->index;
      detections_.push_back(d);
    }
    Settle(context, std::move(found), std::move(age));
    return;
  }
  if (!landmarker_.tracking() && !palm_gate_.Look(context.gray)) {
    // The gate says no new hand can be here: none is found (the hands held
    // from before stay held).
    ++palm_gated_;
    samples_.push_back({{"frame", context.frame->index},
                        {"ms", 0.0},
                        {"palm_gated", true},
                        {"hands", Json::array()}});
    FrameBoxes none;
    none.known = true;
    none.complete = false;
    Settle(context, std::move(none), {});
    return;
  }
  RunModels(context);
}

// A sample the models see: their hands, each with its object evidence.
void LearnedHandDetector::RunModels(FrameContext& context) {
  const std::vector<LandmarkedHand> hands = landmarker_.Detect(context.frame->bgr);
  ++model_samples_;
  const std::size_t detections_before = detections_.size();
  total_ms_ += landmarker_.last_ms();
  FrameBoxes found;
  found.known = true;
  found.complete = false;
  std::vector<int> age;
  Json sample_hands = Json::array();
  for (const LandmarkedHand& hand : hands) {
    if (hand.score < config_.min_score) continue;
    const FingertipEvidence evidence = ObjectEdgesAtFingertips(context.gray, hand, config_);
    const bool touching = evidence.density >= config_.min_object_edges;
    found.hands.push_back(hand.box);
    found.hand_contact.push_back(touching ? 3 : 0);
    if (touching) found.objects.push_back(evidence.box);
    age.push_back(0);
    AddDetection(hand.box, "hand", hand.score, touching ? 3 : 0, context.frame->index);
    if (touching) AddDetection(evidence.box, "object", 1.0, -1, context.frame->index);
    const double s = geometry_.downscale;
    sample_hands.push_back({{"score", Round(hand.score, 1e-3)},
                            {"right", Round(hand.right, 1e-3)},
                            {"object_edges", Round(evidence.density, 1e-4)},
                            {"box", {Round(hand.box.x * s, 0.1), Round(hand.box.y * s, 0.1),
                                     Round(hand.box.br().x * s, 0.1),
                                     Round(hand.box.br().y * s, 0.1)}},
                            {"keypoints", PointsJson(hand.keypoints, s, 0.1)},
                            {"world", PointsJson(hand.world, 1.0, 1e-4)}});
  }
  if (still_every_ > every_) {
    context.gray.copyTo(seen_gray_);
    seen_ordinal_ = context.ordinal;
    seen_frame_ = context.frame->index;
    seen_hands_ = sample_hands;
    seen_found_ = found;
    seen_detections_.assign(
        detections_.begin() + static_cast<std::ptrdiff_t>(detections_before), detections_.end());
  }
  samples_.push_back({{"frame", context.frame->index},
                      {"ms", Round(landmarker_.last_ms(), 0.1)},
                      {"hands", std::move(sample_hands)}});
  Settle(context, std::move(found), std::move(age));
}

// A sample's hands are `found` (ages `age`) plus the ones held from the last
// sample; they hold until the next sample.
void LearnedHandDetector::Settle(FrameContext& context, FrameBoxes found, std::vector<int> age) {
  HoldMissedHands(&found, &age);
  last_ = found;
  last_age_ = std::move(age);
  context.boxes = std::move(found);
}

// A hand of the last sample that no hand of this one overlaps is still
// there: hidden behind something or missed by the models when it was lost
// inside the picture, partly past the border when it was lost next to one
// (its box then reaches that border, which the out-of-frame filter counts
// as cut). Its contact is trusted for hold_samples samples, then unknown
// is taken as none.
void LearnedHandDetector::HoldMissedHands(FrameBoxes* found, std::vector<int>* age) const {
  const double w = geometry_.width, h = geometry_.height;
  const double near_x = config_.border_reach * w, near_y = config_.border_reach * h;
  for (size_t i = 0; i < last_.hands.size(); ++i) {
    if (static_cast<int>(found->hands.size()) >= config_.max_hands) break;
    bool seen = false;
    for (const cv::Rect2d& other : found->hands) seen |= (other & last_.hands[i]).area() > 0;
    if (seen) continue;
    cv::Rect2d box = last_.hands[i];
    double x1 = box.x, y1 = box.y, x2 = box.br().x, y2 = box.br().y;
    if (x1 <= near_x) x1 = 0;
    if (y1 <= near_y) y1 = 0;
    if (x2 >= w - near_x) x2 = w;
    if (y2 >= h - near_y) y2 = h;
    found->hands.emplace_back(cv::Point2d(x1, y1), cv::Point2d(x2, y2));
    const int held = last_age_[i] + 1;
    const bool trusted = held <= config_.hold_samples && last_.hand_contact[i] == 3;
    found->hand_contact.push_back(trusted ? 3 : 0);
    if (trusted) {
      const int o = TouchedObject(last_.hands[i], last_.objects);
      if (o >= 0) found->objects.push_back(last_.objects[o]);
    }
    age->push_back(held);
  }
}

void LearnedHandDetector::AddDetection(const cv::Rect2d& box, const char* kind, double score,
                                       int contact, std::int64_t frame) {
  const double s = geometry_.downscale;
  Detection d;
  d.frame = frame;
  d.kind = kind;
  d.x1 = box.x * s;
  d.y1 = box.y * s;
  d.x2 = box.br().x * s;
  d.y2 = box.br().y * s;
  d.score = score;
  d.contact_state = contact;
  d.source = "detector:learned";
  detections_.push_back(d);
}

Json LearnedHandDetector::Measurements() const {
  const double n = static_cast<double>(samples_.size());
  return {{"model", "mediapipe_hands_" + config_.models},  // the pair that ran
          {"sample_every", every_},
          {"ms_per_sample", n > 0 ? Round(total_ms_ / n, 0.1) : 0.0},
          {"model_samples", model_samples_},
          {"palm_gated", palm_gated_},
          {"samples", samples_}};
}

}  // namespace doasido::filters
