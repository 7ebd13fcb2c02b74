#include "filters/activity.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "filters/verdict.h"

namespace doasido::filters {
namespace {

template <typename T>
std::vector<T> Array(const Json& j, const char* key) {
  if (!j.contains(key) || !j.at(key).is_array()) {
    throw Error("bad_measurements", "missing per-frame array", {.field = key});
  }
  return j.at(key).get<std::vector<T>>();
}

}  // namespace

Json ToJson(const ActivitySignals& s) {
  return Json{{"energy", s.energy}, {"moving", s.moving}, {"hands_region", s.hands_region}};
}

ActivitySignals ActivitySignalsFromJson(const Json& j) {
  ActivitySignals s;
  s.energy = Array<double>(j, "energy");
  s.moving = Array<double>(j, "moving");
  s.hands_region = Array<int>(j, "hands_region");
  if (s.moving.size() != s.energy.size() || s.hands_region.size() != s.energy.size()) {
    throw Error("bad_measurements", "per-frame arrays differ in length", {.field = "activity"});
  }
  return s;
}

double MovingFraction(const cv::Mat& a, const cv::Mat& b, const std::vector<cv::Rect2d>& hands,
                      const ActivitySignalConfig& config) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  const cv::Mat moved = diff > config.pixel_threshold;
  if (hands.empty()) return cv::countNonZero(moved) / (static_cast<double>(a.rows) * a.cols);
  cv::Mat region = cv::Mat::zeros(a.size(), CV_8U);
  const cv::Rect frame(0, 0, a.cols, a.rows);
  for (const cv::Rect2d& box : hands) {
    const double mx = box.width * config.box_margin, my = box.height * config.box_margin;
    const cv::Rect grown(cv::Point(static_cast<int>(std::floor(box.x - mx)),
                                   static_cast<int>(std::floor(box.y - my))),
                         cv::Point(static_cast<int>(std::ceil(box.x + box.width + mx)),
                                   static_cast<int>(std::ceil(box.y + box.height + my))));
    region(grown & frame).setTo(255);
  }
  const int area = cv::countNonZero(region);
  if (area == 0) return cv::countNonZero(moved) / (static_cast<double>(a.rows) * a.cols);
  return cv::countNonZero(moved & region) / static_cast<double>(area);
}

void ActivityExtractor::Consume(FrameContext& context) {
  const cv::Mat& gray = context.gray;
  double energy = 0, moving = 0;
  int hands_region = 0;
  if (!prev_gray_.empty()) {
    cv::absdiff(gray, prev_gray_, diff_);
    cv::Mat region;
    if (context.boxes.known && !context.boxes.hands.empty()) {
      region = cv::Mat::zeros(gray.size(), CV_8U);
      const cv::Rect frame(0, 0, gray.cols, gray.rows);
      for (const cv::Rect2d& b : context.boxes.hands) {
        const double mx = b.width * config_.box_margin, my = b.height * config_.box_margin;
        const cv::Rect grown(cv::Point(static_cast<int>(std::floor(b.x - mx)),
                                       static_cast<int>(std::floor(b.y - my))),
                             cv::Point(static_cast<int>(std::ceil(b.x + b.width + mx)),
                                       static_cast<int>(std::ceil(b.y + b.height + my))));
        region(grown & frame).setTo(255);
      }
      hands_region = cv::countNonZero(region) > 0 ? 1 : 0;
    }
    if (hands_region) {
      const double area = cv::countNonZero(region);
      energy = cv::sum(diff_ & region)[0] / area;  // region is 0/255: & keeps diff inside
      cv::Mat moved = (diff_ > config_.pixel_threshold) & region;
      moving = cv::countNonZero(moved) / area;
    } else {
      const double area = static_cast<double>(gray.rows) * gray.cols;
      energy = cv::sum(diff_)[0] / area;
      moving = cv::countNonZero(diff_ > config_.pixel_threshold) / area;
    }
  }
  signals_.energy.push_back(energy);
  signals_.moving.push_back(moving);
  signals_.hands_region.push_back(hands_region);
  gray.copyTo(prev_gray_);
}

double ActiveFraction(const ActivitySignals& s, double min_moving, std::int64_t first,
                      std::int64_t last) {
  first = std::max<std::int64_t>(first, 1);  // frame 0 has no predecessor
  last = std::min<std::int64_t>(last, static_cast<std::int64_t>(s.moving.size()) - 1);
  if (last < first) return 0;
  std::int64_t active = 0;
  for (std::int64_t i = first; i <= last; ++i) {
    if (s.moving[i] >= min_moving) ++active;
  }
  return static_cast<double>(active) / static_cast<double>(last - first + 1);
}

FilterVerdict DecideActivity(const Json& measurements, const ActivityConfig& c) {
  RequireAnalysis(measurements, kActivityStageName);
  const ActivitySignals s = ActivitySignalsFromJson(measurements.at("signals"));
  const ShotSpan span = SpanOf(measurements, static_cast<std::int64_t>(s.energy.size()));
  const double active = ActiveFraction(s, c.min_moving_fraction, span.first, span.last);
  double mean_energy = 0, hand_frames = 0, n = 0;
  for (std::int64_t i = std::max<std::int64_t>(1, span.first); i <= span.last; ++i) {
    mean_energy += s.energy[i];
    hand_frames += s.hands_region[i];
    ++n;
  }
  n = std::max(n, 1.0);
  FilterVerdict result;
  result.measurements = measurements;
  result.measurements["summary"] = {{"active_fraction", active},
                                    {"mean_energy", mean_energy / n},
                                    {"hand_region_fraction", hand_frames / n},
                                    {"scores",
                                     {ScoreEntry("active_fraction", active, false,
                                                 c.min_active_fraction)}}};
  if (active < c.min_active_fraction) {
    SetVerdict(result, Verdict::kReject, kReasonNoActivity);
  }
  return result;
}

}  // namespace doasido::filters
