#include "filters/hand_landmarker.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "filters/hand_models.h"

namespace doasido::filters {

namespace {

// MediaPipe Hands' graph options.
constexpr double kMinPalmScore = 0.5, kNmsIou = 0.3, kMinPresence = 0.5;
constexpr double kPalmCropScale = 2.6, kPalmCropShift = -0.5;    // palm -> hand crop
constexpr double kTrackCropScale = 2.0, kTrackCropShift = -0.1;  // keypoints -> next crop
constexpr int kPalmWrist = 0, kPalmMiddleBase = 2;  // palm detector keypoints
// A palm whose hand crop overlaps a tracked hand's crop by more than this
// (IoU, unrotated) is that hand (MediaPipe's association threshold).
constexpr double kSameHandIou = 0.5;

using Palm = DetectedPalm;

// SSD anchors of the palm detector: strides 8, 16, 16, 16, two anchors per
// layer and cell, fixed size, centred in their cell.
std::vector<cv::Point2d> PalmAnchors() {
  std::vector<cv::Point2d> anchors;
  const int strides[] = {8, 16, 16, 16};
  for (std::size_t layer = 0; layer < 4;) {
    int per_cell = 0;
    const int stride = strides[layer];
    while (layer < 4 && strides[layer] == stride) {
      per_cell += 2;
      ++layer;
    }
    const int cells = (kPalmInputSize + stride - 1) / stride;
    for (int y = 0; y < cells; ++y) {
      for (int x = 0; x < cells; ++x) {
        for (int a = 0; a < per_cell; ++a) {
          anchors.emplace_back((x + 0.5) / cells, (y + 0.5) / cells);
        }
      }
    }
  }
  return anchors;
}

// Bilinear sample of an RGB frame into a size x size float tensor in [0, 1]
// through an affine map from output pixel centres to frame coordinates
// (frame pixel centres at +0.5); taps outside the frame count as black.
// Single precision, the source position stepped along each row (the
// models' input is fp32; this runs once per model run).
void SampleRgb(const cv::Mat& rgb, int size, const cv::Matx23d& map, std::vector<float>* out) {
  out->resize(static_cast<std::size_t>(size) * size * 3);
  const int cols = rgb.cols, rows = rgb.rows;
  const float du_x = static_cast<float>(map(0, 0)), du_y = static_cast<float>(map(1, 0));
  constexpr float kScale = 1.0f / 255;
  for (int v = 0; v < size; ++v) {
    // Row start in double (no drift from one row to the next).
    const double row_x = map(0, 0) * 0.5 + map(0, 1) * (v + 0.5) + map(0, 2) - 0.5;
    const double row_y = map(1, 0) * 0.5 + map(1, 1) * (v + 0.5) + map(1, 2) - 0.5;
    float* o = out->data() + static_cast<std::size_t>(v) * size * 3;
    for (int u = 0; u < size; ++u, o += 3) {
      const float fx = static_cast<float>(row_x) + du_x * u;
      const float fy = static_cast<float>(row_y) + du_y * u;
      const float flx = std::floor(fx), fly = std::floor(fy);
      const int x0 = static_cast<int>(flx), y0 = static_cast<int>(fly);
      const float ax = fx - flx, ay = fy - fly;
      o[0] = o[1] = o[2] = 0.f;
      if (x0 >= 0 && y0 >= 0 && x0 + 1 < cols && y0 + 1 < rows) {
        const std::uint8_t* p0 = rgb.ptr<std::uint8_t>(y0) + 3 * x0;
        const std::uint8_t* p1 = rgb.ptr<std::uint8_t>(y0 + 1) + 3 * x0;
        const float w00 = (1 - ay) * (1 - ax) * kScale, w01 = (1 - ay) * ax * kScale;
        const float w10 = ay * (1 - ax) * kScale, w11 = ay * ax * kScale;
        for (int c = 0; c < 3; ++c) {
          o[c] = w00 * p0[c] + w01 * p0[3 + c] + w10 * p1[c] + w11 * p1[3 + c];
        }
        continue;
      }
      for (int dy = 0; dy < 2; ++dy) {
        const int y = y0 + dy;
        if (y < 0 || y >= rows) continue;
        const float wy = dy ? ay : 1 - ay;
        const std::uint8_t* row = rgb.ptr<std::uint8_t>(y);
        for (int dx = 0; dx < 2; ++dx) {
          const int x = x0 + dx;
          if (x < 0 || x >= cols) continue;
          const float w = wy * (dx ? ax : 1 - ax) * kScale;
          const std::uint8_t* p = row + 3 * x;
          for (int c = 0; c < 3; ++c) o[c] += w * p[c];
        }
      }
    }
  }
}

double IoU(const cv::Rect2d& a, const cv::Rect2d& b) {
  const double inter = (a & b).area();
  const double uni = a.area() + b.area() - inter;
  return uni > 0 ? inter / uni : 0;
}

// Weighted non-maximum suppression: each kept palm is the score-weighted
// mean of the candidates overlapping the best one.
std::vector<Palm> WeightedNms(std::vector<Palm> candidates) {
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Palm& a, const Palm& b) { return a.score > b.score; });
  std::vector<Palm> kept;
  while (!candidates.empty()) {
    const Palm best = candidates.front();
    std::vector<Palm> group, rest;
    for (const Palm& c : candidates) (IoU(c.box, best.box) > kNmsIou ? group : rest).push_back(c);
    candidates = std::move(rest);
    double total = 0, x1 = 0, y1 = 0, x2 = 0, y2 = 0;
    Palm mean;
    mean.score = best.score;
    for (const Palm& c : group) {
      total += c.score;
      x1 += c.score * c.box.x;
      y1 += c.score * c.box.y;
      x2 += c.score * c.box.br().x;
      y2 += c.score * c.box.br().y;
      for (int k = 0; k < 7; ++k) mean.keypoints[k] += c.score * c.keypoints[k];
    }
    mean.box = cv::Rect2d(cv::Point2d(x1, y1) / total, cv::Point2d(x2, y2) / total);
    for (cv::Point2d& p : mean.keypoints) p /= total;
    kept.push_back(mean);
  }
  return kept;
}

double NormalizeAngle(double a) { return a - 2 * M_PI * std::floor((a + M_PI) / (2 * M_PI)); }

// Angle that turns the wrist -> middle-finger direction upright.
double UprightAngle(const cv::Point2d& wrist, const cv::Point2d& middle) {
  return NormalizeAngle(M_PI / 2 - std::atan2(-(middle.y - wrist.y), middle.x - wrist.x));
}

HandCrop CropFrom(double cx, double cy, double w, double h, double rotation, double scale,
                  double shift_y) {
  cx -= h * shift_y * std::sin(rotation);
  cy += h * shift_y * std::cos(rotation);
  return {cx, cy, std::max(w, h) * scale, rotation};
}

// The crop to look for a hand in the next frame: from the palm's keypoints
// (wrist, thumb base, finger bases and middle joints), upright, doubled.
HandCrop CropFromHand(const LandmarkedHand& hand) {
  constexpr int ids[] = {0, 1, 2, 3, 5, 6, 9, 10, 13, 14, 17, 18};
  const auto point = [&](int k) { return cv::Point2d(hand.keypoints[k].x, hand.keypoints[k].y); };
  const double rotation = UprightAngle(point(kWrist), point(kMiddleBase));
  const double c = std::cos(rotation), s = std::sin(rotation);
  double min_u = INFINITY, max_u = -INFINITY, min_v = INFINITY, max_v = -INFINITY;
  for (int i : ids) {
    const cv::Point2d p = point(i);
    const double u = p.x * c + p.y * s, v = -p.x * s + p.y * c;
    min_u = std::min(min_u, u);
    max_u = std::max(max_u, u);
    min_v = std::min(min_v, v);
    max_v = std::max(max_v, v);
  }
  const double mu = (min_u + max_u) / 2, mv = (min_v + max_v) / 2;
  return CropFrom(mu * c - mv * s, mu * s + mv * c, max_u - min_u, max_v - min_v, rotation,
                  kTrackCropScale, kTrackCropShift);
}

// Crop pixel (u, v) -> frame: centre + rotation of ((u, v) / size - 0.5) * side.
cv::Matx23d CropMap(const HandCrop& crop) {
  const double c = std::cos(crop.rotation), s = std::sin(crop.rotation);
  const double k = crop.side / kLandmarkInputSize;
  return {k * c, -k * s, crop.cx - crop.side / 2 * (c - s),
          k * s, k * c,  crop.cy - crop.side / 2 * (s + c)};
}

// The fraction of pixels of two input tensors (RGB in [0, 1]) where some
// channel differs by more than `level` gray levels.
double ChangedFraction(const std::vector<float>& a, const std::vector<float>& b, int level) {
  const float limit = level / 255.0f;
  std::size_t changed = 0;
  for (std::size_t i = 0; i + 2 < a.size(); i += 3) {
    changed += std::abs(a[i] - b[i]) > limit || std::abs(a[i + 1] - b[i + 1]) > limit ||
               std::abs(a[i + 2] - b[i + 2]) > limit;
  }
  return a.empty() ? 1.0 : static_cast<double>(changed) / (a.size() / 3);
}

// Stretches an input tensor (RGB in [0, 1]) so that its brightness's 2nd
// to 98th percentile spans [0, 1], when that span is below kLowContrast;
// false (the tensor untouched) when it is not.
bool StretchLowContrast(std::vector<float>* input) {
  int histogram[256] = {};
  const std::size_t pixels = input->size() / 3;
  for (std::size_t i = 0; i < pixels; ++i) {
    const float* p = input->data() + 3 * i;
    ++histogram[std::clamp(static_cast<int>((p[0] + p[1] + p[2]) / 3 * 255 + 0.5f), 0, 255)];
  }
  const auto percentile = [&](double q) {
    std::size_t seen = 0;
    for (int v = 0; v < 256; ++v) {
      seen += histogram[v];
      if (seen >= q * pixels) return v / 255.0f;
    }
    return 1.0f;
  };
  const float lo = percentile(0.02), hi = percentile(0.98);
  if (hi - lo >= kLowContrast || hi - lo < 1e-3f) return false;
  for (float& v : *input) v = std::clamp((v - lo) / (hi - lo), 0.0f, 1.0f);
  return true;
}

// The wide search's zoomed windows over a cols x rows frame: squares of
// half the longer side (at most the shorter side), half a window apart,
// spread evenly from edge to edge.
std::vector<cv::Rect> ZoomWindows(int cols, int rows) {
  const int side = std::min(std::max(cols, rows) / 2, std::min(cols, rows));
  const auto starts = [side](int length) {
    const int n = (length - side + side / 2 - 1) / (side / 2) + 1;
    std::vector<int> out;
    for (int i = 0; i < n; ++i) out.push_back(n == 1 ? 0 : (length - side) * i / (n - 1));
    return out;
  };
  std::vector<cv::Rect> windows;
  if (side < kPalmInputSize / 2) return windows;  // too small to zoom into
  for (int y : starts(rows)) {
    for (int x : starts(cols)) windows.emplace_back(x, y, side, side);
  }
  return windows;
}

// The hand crop a palm gives (MediaPipe's palm -> hand crop).
HandCrop PalmCrop(const DetectedPalm& p) {
  return CropFrom(p.box.x + p.box.width / 2, p.box.y + p.box.height / 2, p.box.width,
                  p.box.height, UprightAngle(p.keypoints[kPalmWrist], p.keypoints[kPalmMiddleBase]),
                  kPalmCropScale, kPalmCropShift);
}

cv::Rect2d CropSquare(const HandCrop& c) {
  return cv::Rect2d(c.cx - c.side / 2, c.cy - c.side / 2, c.side, c.side);
}

LandmarkedHand Scaled(LandmarkedHand hand, double scale) {
  hand.box = cv::Rect2d(hand.box.tl() * scale, hand.box.br() * scale);
  for (cv::Point3d& p : hand.keypoints) p *= scale;
  return hand;
}

}  // namespace

bool HandLandmarkerAvailable(std::string* why) {
  std::string native_why, wasm_why;
  if (HandModelFilesAvailable(&native_why) || WasmHandModelsAvailable(&wasm_why)) return true;
  if (why) *why = native_why + "; " + wasm_why;
  return false;
}

HandLandmarker::HandLandmarker(HandLandmarkerOptions options)
    : options_(std::move(options)),
      models_(MakeHandModels(options_.backend, options_.clip, true, &note_, options_.models)),
      anchors_(PalmAnchors()) {}

HandLandmarker::~HandLandmarker() = default;

const char* HandLandmarker::backend() const { return models_->backend(); }

void HandLandmarker::Reset() {
  tracked_.clear();
  since_palms_ = 0;
  searching_ = 0;
  lost_wide_left_ = 0;
  frames_ = 0;
  handless_ = 0;
}

std::vector<DetectedPalm> HandLandmarker::Palms(const cv::Mat& rgb) {
  const double scale = std::min(static_cast<double>(kPalmInputSize) / rgb.cols,
                                static_cast<double>(kPalmInputSize) / rgb.rows);
  const double pad_x = (kPalmInputSize - rgb.cols * scale) / 2;
  const double pad_y = (kPalmInputSize - rgb.rows * scale) / 2;
  SampleRgb(rgb, kPalmInputSize, {1 / scale, 0, -pad_x / scale, 0, 1 / scale, -pad_y / scale},
            &input_);
  PalmOutput out;
  models_->Palm(input_.data(), &out);
  const auto to_frame = [&](double x, double y) {
    return cv::Point2d((x * kPalmInputSize - pad_x) / scale, (y * kPalmInputSize - pad_y) / scale);
  };
  std::vector<Palm> candidates;
  for (std::size_t i = 0; i < anchors_.size() && i < out.logits.size(); ++i) {
    // A logit below -1e-6 scores below 0.4999998: no exp() for the
    // thousands of anchors far from any palm.
    if (out.logits[i] < -1e-6f) continue;
    const double score = 1 / (1 + std::exp(-std::clamp<double>(out.logits[i], -100, 100)));
    if (score < kMinPalmScore) continue;
    const float* r = out.regressors.data() + i * kPalmValues;
    const cv::Point2d a = anchors_[i];
    const double cx = r[0] / kPalmInputSize + a.x, cy = r[1] / kPalmInputSize + a.y;
    const double w = r[2] / kPalmInputSize, h = r[3] / kPalmInputSize;
    Palm p;
    p.score = score;
    p.box = cv::Rect2d(to_frame(cx - w / 2, cy - h / 2), to_frame(cx + w / 2, cy + h / 2));
    for (int k = 0; k < 7; ++k) {
      p.keypoints[k] =
          to_frame(r[4 + 2 * k] / kPalmInputSize + a.x, r[5 + 2 * k] / kPalmInputSize + a.y);
    }
    candidates.push_back(p);
  }
  return WeightedNms(std::move(candidates));
}

std::vector<DetectedPalm> HandLandmarker::DetectPalms(const cv::Mat& bgr) {
  double shrink = 1;
  std::vector<DetectedPalm> palms = Palms(Rgb(bgr, &shrink));
  for (DetectedPalm& p : palms) {
    p.box = cv::Rect2d(p.box.tl() / shrink, p.box.br() / shrink);
    for (cv::Point2d& k : p.keypoints) k /= shrink;
  }
  return palms;
}

bool HandLandmarker::Landmarks(const cv::Mat& rgb, const HandCrop& crop, LandmarkedHand* hand,
                               bool stretch) {
  const cv::Matx23d map = CropMap(crop);
  const double k = crop.side / kLandmarkInputSize;
  SampleRgb(rgb, kLandmarkInputSize, map, &input_);
  if (stretch && !StretchLowContrast(&input_)) return false;  // not low in contrast: no new look
  LandmarkOutput out;
  models_->Landmark(input_.data(), &out);
  if (out.presence < kMinPresence) return false;
  hand->score = out.presence;
  hand->right = out.right;
  double x1 = INFINITY, y1 = INFINITY, x2 = -INFINITY, y2 = -INFINITY;
  for (int i = 0; i < kHandKeypoints; ++i) {
    const double u = out.screen[3 * i], v = out.screen[3 * i + 1];
    const double x = map(0, 0) * u + map(0, 1) * v + map(0, 2);
    const double y = map(1, 0) * u + map(1, 1) * v + map(1, 2);
    hand->keypoints[i] = {x, y, out.screen[3 * i + 2] * k};
    hand->world[i] = {out.world[3 * i], out.world[3 * i + 1], out.world[3 * i + 2]};
    x1 = std::min(x1, x);
    y1 = std::min(y1, y);
    x2 = std::max(x2, x);
    y2 = std::max(y2, y);
  }
  hand->box = cv::Rect2d(cv::Point2d(x1, y1), cv::Point2d(x2, y2));
  return true;
}

std::vector<TrackedHand> HandLandmarker::WideSearch(const cv::Mat& rgb,
                                                    const std::vector<LandmarkedHand>& known) {
  ++wide_searches_;
  std::vector<TrackedHand> found;
  // A crop on a hand already found, or one this search found: no new look.
  const auto seen = [&](const HandCrop& crop) {
    for (const LandmarkedHand& h : known) {
      if (IoU(CropSquare(CropFromHand(h)), CropSquare(crop)) > kSameHandIou) return true;
    }
    for (const TrackedHand& t : found) {
      if (IoU(CropSquare(t.run_crop), CropSquare(crop)) > kSameHandIou) return true;
    }
    return false;
  };
  const auto enough = [&] {
    return static_cast<int>(known.size() + found.size()) >= options_.max_hands;
  };
  // A candidate crop is a hand when the landmark model finds one on it
  // (as is, else stretched when low in contrast) and again on the crop its
  // keypoints give.
  const auto look = [&](const HandCrop& crop) {
    if (seen(crop)) return false;
    for (const bool stretch : {false, true}) {
      LandmarkedHand first, hand;
      if (!Landmarks(rgb, crop, &first, stretch)) continue;
      const HandCrop own = CropFromHand(first);
      if (!Landmarks(rgb, own, &hand, stretch)) continue;
      if (seen(own)) return true;  // a hand already found, from another crop
      found.push_back({.run_crop = own, .run_hand = hand});
      return true;
    }
    return false;
  };
  for (const cv::Rect& window : ZoomWindows(rgb.cols, rgb.rows)) {
    if (enough()) break;
    for (DetectedPalm palm : Palms(rgb(window))) {
      palm.box.x += window.x;
      palm.box.y += window.y;
      for (cv::Point2d& k : palm.keypoints) k += cv::Point2d(window.tl());
      look(PalmCrop(palm));
    }
  }
  // No palm at all: the whole frame, letterboxed, and its centred square,
  // upright first, then turned (stops at the first turn that finds a hand).
  const double cx = rgb.cols / 2.0, cy = rgb.rows / 2.0;
  for (const int side : {std::max(rgb.cols, rgb.rows), std::min(rgb.cols, rgb.rows)}) {
    for (const double turn : {0.0, M_PI / 2, -M_PI / 2, M_PI}) {
      if (enough() || look({cx, cy, static_cast<double>(side), turn})) break;
    }
  }
  std::stable_sort(found.begin(), found.end(), [](const TrackedHand& a, const TrackedHand& b) {
    return a.run_hand.score > b.run_hand.score;
  });
  return found;
}

bool HandLandmarker::WideDue() {
  if (options_.wide_every <= 0 || !tracked_.empty()) return false;
  if (frames_ > 0 && ++handless_ < options_.wide_every) return false;
  handless_ = 0;
  return true;
}

// The tracked hand's last landmark crop, sampled again from this frame,
// barely changed: the model would see (nearly) what it saw.
bool HandLandmarker::CropUnchanged(const cv::Mat& rgb, const TrackedHand& track) {
  if (options_.unchanged_crop_fraction <= 0 || track.run_input.empty()) return false;
  SampleRgb(rgb, kLandmarkInputSize, CropMap(track.run_crop), &compare_);
  return ChangedFraction(compare_, track.run_input, options_.unchanged_crop_level) <=
         options_.unchanged_crop_fraction;
}

cv::Mat HandLandmarker::Rgb(const cv::Mat& bgr, double* shrink) const {
  if (bgr.empty() || bgr.type() != CV_8UC3) {
    throw Error("hand_detector_failed", "the hand detector needs a BGR frame of 8-bit pixels",
                {.clip = options_.clip});
  }
  *shrink = std::min(1.0, static_cast<double>(options_.max_side) / std::max(bgr.cols, bgr.rows));
  cv::Mat rgb;
  if (*shrink < 1.0) {
    cv::Mat small;
    cv::resize(bgr, small, {}, *shrink, *shrink, cv::INTER_AREA);
    cv::cvtColor(small, rgb, cv::COLOR_BGR2RGB);
  } else {
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  }
  return rgb;
}

std::vector<LandmarkedHand> HandLandmarker::Detect(const cv::Mat& bgr) {
  double shrink = 1;
  const cv::Mat rgb = Rgb(bgr, &shrink);
  return DetectRgb(rgb, shrink, WideDue());
}

std::vector<LandmarkedHand> HandLandmarker::DetectStill(const cv::Mat& image) {
  cv::Mat bgr = image;
  if (image.type() == CV_8UC1) cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  if (image.type() == CV_8UC4) cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
  Reset();
  double shrink = 1;
  const cv::Mat rgb = Rgb(bgr, &shrink);
  return DetectRgb(rgb, shrink, true);
}

std::vector<LandmarkedHand> HandLandmarker::DetectRgb(const cv::Mat& rgb, double shrink,
                                                      bool wide) {
  models_->TakeModelMs();
  std::vector<LandmarkedHand> hands;
  std::vector<TrackedHand> runs;  // per hand found: its last landmark run
  const auto add = [&](const LandmarkedHand& hand, TrackedHand run) {
    for (const LandmarkedHand& h : hands) {
      if (IoU(h.box, hand.box) >= 0.5) return;
    }
    hands.push_back(hand);
    runs.push_back(std::move(run));
  };
  const auto consider = [&](const HandCrop& crop) {
    LandmarkedHand hand;
    if (!Landmarks(rgb, crop, &hand)) return;
    TrackedHand run{.run_crop = crop, .run_hand = hand};
    if (options_.unchanged_crop_fraction > 0) run.run_input = input_;  // kept only to compare
    add(hand, std::move(run));
  };
  for (TrackedHand& track : tracked_) {
    if (!CropUnchanged(rgb, track)) {
      consider(track.next);
      continue;
    }
    ++reused_;
    add(track.run_hand, std::move(track));
  }
  // A hand lost on this frame is looked for on this frame and the next
  // lost_search - 1 (until max_hands hands are tracked).
  if (hands.size() < tracked_.size()) {
    searching_ = options_.lost_search;
    lost_wide_left_ = options_.lost_wide;
  }
  if (lost_wide_left_ > 0) {
    --lost_wide_left_;
    wide = true;
  }
  ++since_palms_;
  if (static_cast<int>(hands.size()) < options_.max_hands &&
      (hands.empty() || searching_ > 0 || since_palms_ >= options_.palm_every)) {
    since_palms_ = 0;
    for (const Palm& p : Palms(rgb)) {
      if (static_cast<int>(hands.size()) >= options_.max_hands) break;
      const HandCrop crop = PalmCrop(p);
      // A palm of a hand already found: no landmark run (MediaPipe's association).
      bool known = false;
      for (const LandmarkedHand& h : hands) {
        known |= IoU(CropSquare(CropFromHand(h)), CropSquare(crop)) > kSameHandIou;
      }
      if (!known) consider(crop);
    }
  }
  if (wide && static_cast<int>(hands.size()) < options_.max_hands) {
    for (TrackedHand& run : WideSearch(rgb, hands)) {
      if (static_cast<int>(hands.size()) >= options_.max_hands) break;
      bool known = false;
      for (const LandmarkedHand& h : hands) {
        known |= IoU(CropSquare(CropFromHand(h)), CropSquare(run.run_crop)) > kSameHandIou;
      }
      if (known) continue;
      const std::size_t before = hands.size();
      add(run.run_hand, std::move(run));
      wide_found_ += static_cast<int>(hands.size() - before);
    }
  }
  ++frames_;
  if (searching_ > 0) --searching_;
  if (static_cast<int>(hands.size()) >= options_.max_hands) searching_ = lost_wide_left_ = 0;
  tracked_ = std::move(runs);
  for (std::size_t i = 0; i < hands.size(); ++i) tracked_[i].next = CropFromHand(hands[i]);
  last_ms_ = models_->TakeModelMs();
  for (LandmarkedHand& h : hands) h = Scaled(h, 1.0 / shrink);
  return hands;
}

}  // namespace doasido::filters
