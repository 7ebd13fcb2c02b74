#include "filters/camera_motion.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "core/error.h"
#include "filters/verdict.h"

namespace doasido::filters {
namespace {

template <typename T>
std::vector<T> Array(const Json& j, const char* key) {
  if (!j.contains(key) || !j.at(key).is_array()) {
    throw Error("bad_measurements", "missing per-pair array", {.field = key});
  }
  return j.at(key).get<std::vector<T>>();
}

void ExcludeBoxes(const std::vector<cv::Rect2d>& boxes, double margin, cv::Mat& mask) {
  const cv::Rect frame(0, 0, mask.cols, mask.rows);
  for (const cv::Rect2d& b : boxes) {
    const double mx = b.width * margin, my = b.height * margin;
    const cv::Rect grown(
        cv::Point(static_cast<int>(std::floor(b.x - mx)), static_cast<int>(std::floor(b.y - my))),
        cv::Point(static_cast<int>(std::ceil(b.x + b.width + mx)),
                  static_cast<int>(std::ceil(b.y + b.height + my))));
    mask(grown & frame).setTo(0);
  }
}

// The steps of CameraMotionExtractor::Consume.

// The camera's motion between two sampled frames, as the signals store it.
struct PairMotion {
  double tx = 0, ty = 0, rotation = 0, log_scale = 0;
  int points = 0, inliers = 0, valid = 0;
  int masked = 0;  // corners came from the background only (hands and objects masked)
};

// Corners to track in `prev_gray`: from the background when `prev_mask`
// leaves enough of them (`masked` = 1), else from the whole frame.
std::vector<cv::Point2f> Corners(const cv::Mat& prev_gray, const cv::Mat& prev_mask,
                                 const CameraMotionSignalConfig& config, int& masked) {
  std::vector<cv::Point2f> corners;
  if (!prev_mask.empty()) {
    cv::goodFeaturesToTrack(prev_gray, corners, config.max_corners, config.quality_level,
                            config.min_distance, prev_mask);
    masked = static_cast<int>(corners.size()) >= config.min_background_points ? 1 : 0;
  }
  if (!masked) {
    cv::goodFeaturesToTrack(prev_gray, corners, config.max_corners, config.quality_level,
                            config.min_distance);
  }
  return corners;
}

// The frame-to-frame homography (or similarity) of the tracked corners by
// RANSAC at `threshold` pixels; false when none fits.
bool FitFrameMotion(const std::vector<cv::Point2f>& src, const std::vector<cv::Point2f>& dst,
                    const CameraMotionSignalConfig& config, double threshold, cv::Matx33d& h,
                    cv::Mat& inlier_mask) {
  if (config.model == "similarity") {
    cv::Mat a = cv::estimateAffinePartial2D(src, dst, inlier_mask, cv::RANSAC, threshold);
    if (a.empty()) return false;
    for (int r = 0; r < 2; ++r) {
      for (int c = 0; c < 3; ++c) h(r, c) = a.at<double>(r, c);
    }
    return true;
  }
  cv::Mat m = cv::findHomography(src, dst, cv::RANSAC, threshold, inlier_mask);
  if (m.empty() || std::abs(m.at<double>(2, 2)) <= 1e-12) return false;
  h = cv::Matx33d(m) * (1.0 / m.at<double>(2, 2));
  return true;
}

// Tracks `corners` from `prev_gray` into `gray` and fills `m` with the
// fitted motion of the frame centre (shift as a fraction of the diagonal,
// rotation, log scale).
void MotionBetween(const cv::Mat& prev_gray, const cv::Mat& gray,
                   const std::vector<cv::Point2f>& corners, const CameraMotionSignalConfig& config,
                   double downscale, PairMotion& m) {
  std::vector<cv::Point2f> tracked;
  std::vector<unsigned char> status;
  std::vector<float> error;
  cv::calcOpticalFlowPyrLK(prev_gray, gray, corners, tracked, status, error,
                           cv::Size(config.lk_window, config.lk_window), config.lk_levels,
                           cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                            config.lk_iterations, config.lk_epsilon));
  std::vector<cv::Point2f> src, dst;
  for (size_t i = 0; i < corners.size(); ++i) {
    if (status[i]) {
      src.push_back(corners[i]);
      dst.push_back(tracked[i]);
    }
  }
  m.points = static_cast<int>(src.size());
  const double threshold = std::max(0.5, config.ransac_threshold / std::max(1.0, downscale));
  if (m.points < config.min_points) return;
  cv::Mat inlier_mask;
  cv::Matx33d h = cv::Matx33d::eye();
  if (!FitFrameMotion(src, dst, config, threshold, h, inlier_mask)) return;
  m.inliers = cv::countNonZero(inlier_mask);
  const double cx = gray.cols / 2.0, cy = gray.rows / 2.0;
  const cv::Vec3d c = h * cv::Vec3d(cx, cy, 1.0);
  const double diagonal = std::hypot(gray.cols, gray.rows);
  m.tx = (c[0] / c[2] - cx) / diagonal;
  m.ty = (c[1] / c[2] - cy) / diagonal;
  m.rotation = std::atan2(h(1, 0) - h(0, 1), h(0, 0) + h(1, 1));
  const double det = std::abs(h(0, 0) * h(1, 1) - h(0, 1) * h(1, 0));
  m.log_scale = det > 0 ? 0.5 * std::log(det) : 0.0;
  m.valid = 1;
}

}  // namespace

Json ToJson(const CameraMotionSignals& s) {
  return Json{{"step", s.step},
              {"frame", s.frame},
              {"dt_s", s.dt_s},
              {"tx", s.tx},
              {"ty", s.ty},
              {"rotation", s.rotation},
              {"log_scale", s.log_scale},
              {"points", s.points},
              {"inliers", s.inliers},
              {"valid", s.valid},
              {"masked", s.masked}};
}

CameraMotionSignals CameraMotionSignalsFromJson(const Json& j) {
  CameraMotionSignals s;
  s.step = j.value("step", 1);
  s.frame = Array<std::int64_t>(j, "frame");
  s.dt_s = Array<double>(j, "dt_s");
  s.tx = Array<double>(j, "tx");
  s.ty = Array<double>(j, "ty");
  s.rotation = Array<double>(j, "rotation");
  s.log_scale = Array<double>(j, "log_scale");
  s.points = Array<int>(j, "points");
  s.inliers = Array<int>(j, "inliers");
  s.valid = Array<int>(j, "valid");
  s.masked = Array<int>(j, "masked");
  const size_t n = s.frame.size();
  if (s.dt_s.size() != n || s.tx.size() != n || s.ty.size() != n || s.rotation.size() != n ||
      s.log_scale.size() != n || s.points.size() != n || s.inliers.size() != n ||
      s.valid.size() != n || s.masked.size() != n) {
    throw Error("bad_measurements", "per-pair arrays differ in length", {.field = "camera_motion"});
  }
  return s;
}

void CameraMotionExtractor::Begin(const VideoGeometry& geometry) {
  geometry_ = geometry;
  const double fps = geometry.fps > 0 ? geometry.fps : 30.0;
  signals_.step = std::max(1, static_cast<int>(std::lround(fps / config_.sample_fps)));
}

void CameraMotionExtractor::Consume(FrameContext& context) {
  if (context.ordinal % signals_.step != 0) return;
  const cv::Mat& gray = context.gray;
  cv::Mat mask;
  if (context.boxes.known && (!context.boxes.hands.empty() || !context.boxes.objects.empty())) {
    mask = cv::Mat(gray.size(), CV_8U, cv::Scalar(255));
    ExcludeBoxes(context.boxes.hands, config_.box_margin, mask);
    ExcludeBoxes(context.boxes.objects, config_.box_margin, mask);
  }
  const double time = context.frame->timestamp_s;
  if (!prev_gray_.empty()) {
    PairMotion m;
    const std::vector<cv::Point2f> corners = Corners(prev_gray_, prev_mask_, config_, m.masked);
    if (static_cast<int>(corners.size()) >= config_.min_points) {
      MotionBetween(prev_gray_, gray, corners, config_, geometry_.downscale, m);
    }
    signals_.frame.push_back(context.ordinal);
    signals_.dt_s.push_back(time - prev_time_);
    signals_.tx.push_back(m.tx);
    signals_.ty.push_back(m.ty);
    signals_.rotation.push_back(m.rotation);
    signals_.log_scale.push_back(m.log_scale);
    signals_.points.push_back(m.points);
    signals_.inliers.push_back(m.inliers);
    signals_.valid.push_back(m.valid);
    signals_.masked.push_back(m.masked);
  }
  gray.copyTo(prev_gray_);
  prev_mask_ = mask;
  prev_time_ = time;
}

CameraMotionSummary SummarizeCameraMotion(const CameraMotionSignals& s, const ShotSpan& span) {
  CameraMotionSummary out;
  double sum_tx = 0, sum_ty = 0, inlier_ratio_sum = 0;
  int valid = 0;
  for (size_t i = 0; i < s.frame.size(); ++i) {
    // Only pairs inside the kept shot, and none across a shot boundary.
    const std::int64_t from = s.frame[i] - s.step, to = s.frame[i];
    if (!span.Contains(from) || !span.Contains(to)) continue;
    // Boundaries are placed mid-transition: keep clear of a dissolve's ends too.
    const std::int64_t margin = std::max<std::int64_t>(3, s.step / 2);
    bool across = false;
    for (std::int64_t b : span.boundaries) across |= b > from - margin && b <= to + margin;
    if (across) continue;
    ++out.pairs;
    const double dt = s.dt_s[i] > 0 ? s.dt_s[i] : 1e-3;
    out.duration_s += s.dt_s[i] > 0 ? s.dt_s[i] : 0;
    if (!s.valid[i]) continue;
    ++valid;
    const double t = std::hypot(s.tx[i], s.ty[i]);
    out.cumulative_translation += t;
    out.cumulative_rotation += std::abs(s.rotation[i]);
    out.cumulative_scale += std::abs(s.log_scale[i]);
    sum_tx += s.tx[i];
    sum_ty += s.ty[i];
    out.peak_translation_rate = std::max(out.peak_translation_rate, t / dt);
    out.peak_rotation_rate = std::max(out.peak_rotation_rate, std::abs(s.rotation[i]) / dt);
    out.peak_scale_rate = std::max(out.peak_scale_rate, std::abs(s.log_scale[i]) / dt);
    inlier_ratio_sum += s.points[i] > 0 ? static_cast<double>(s.inliers[i]) / s.points[i] : 0;
  }
  out.net_translation = std::hypot(sum_tx, sum_ty);
  if (out.duration_s > 0) {
    out.translation_rate = out.cumulative_translation / out.duration_s;
    out.rotation_rate = out.cumulative_rotation / out.duration_s;
    out.scale_rate = out.cumulative_scale / out.duration_s;
  }
  out.valid_fraction = out.pairs > 0 ? static_cast<double>(valid) / out.pairs : 0;
  out.mean_inlier_ratio = valid > 0 ? inlier_ratio_sum / valid : 0;
  return out;
}

FilterVerdict DecideCameraMotion(const Json& measurements, const CameraMotionConfig& c) {
  RequireAnalysis(measurements, kCameraMotionStageName);
  const CameraMotionSignals s = CameraMotionSignalsFromJson(measurements.at("signals"));
  const std::int64_t frames =
      static_cast<std::int64_t>(NumberOr(measurements.at("clip"), "frames", 0));
  const CameraMotionSummary m = SummarizeCameraMotion(s, SpanOf(measurements, frames));
  FilterVerdict result;
  result.measurements = measurements;
  result.measurements["summary"] = {{"pairs", m.pairs},
                                    {"duration_s", m.duration_s},
                                    {"cumulative_translation", m.cumulative_translation},
                                    {"net_translation", m.net_translation},
                                    {"cumulative_rotation", m.cumulative_rotation},
                                    {"cumulative_scale", m.cumulative_scale},
                                    {"translation_rate", m.translation_rate},
                                    {"rotation_rate", m.rotation_rate},
                                    {"scale_rate", m.scale_rate},
                                    {"peak_translation_rate", m.peak_translation_rate},
                                    {"peak_rotation_rate", m.peak_rotation_rate},
                                    {"peak_scale_rate", m.peak_scale_rate},
                                    {"mean_inlier_ratio", m.mean_inlier_ratio},
                                    {"valid_fraction", m.valid_fraction},
                                    {"scores",
                                     {ScoreEntry("translation_rate", m.translation_rate, true,
                                                 c.reject_translation_rate,
                                                 c.flag_translation_rate),
                                      ScoreEntry("rotation_rate", m.rotation_rate, true,
                                                 c.reject_rotation_rate, c.flag_rotation_rate),
                                      ScoreEntry("scale_rate", m.scale_rate, true,
                                                 c.reject_scale_rate, c.flag_scale_rate),
                                      ScoreEntry("peak_translation_rate",
                                                 m.peak_translation_rate, true,
                                                 c.reject_peak_translation_rate),
                                      ScoreEntry("peak_rotation_rate", m.peak_rotation_rate,
                                                 true, c.reject_peak_rotation_rate),
                                      ScoreEntry("peak_scale_rate", m.peak_scale_rate, true,
                                                 c.reject_peak_scale_rate)}}};
  const bool reject = m.translation_rate >= c.reject_translation_rate ||
                      m.rotation_rate >= c.reject_rotation_rate ||
                      m.scale_rate >= c.reject_scale_rate ||
                      m.peak_translation_rate >= c.reject_peak_translation_rate ||
                      m.peak_rotation_rate >= c.reject_peak_rotation_rate ||
                      m.peak_scale_rate >= c.reject_peak_scale_rate;
  const bool flag = m.translation_rate >= c.flag_translation_rate ||
                    m.rotation_rate >= c.flag_rotation_rate || m.scale_rate >= c.flag_scale_rate;
  if (reject) {
    SetVerdict(result, Verdict::kReject, kReasonCameraMotion);
  } else if (m.pairs > 0 && m.valid_fraction < c.min_valid_fraction) {
    SetVerdict(result, Verdict::kFlag, kReasonCameraMotionUnknown);
  } else if (flag) {
    SetVerdict(result, Verdict::kFlag, kReasonCameraMotion);
  }
  return result;
}

}  // namespace doasido::filters
