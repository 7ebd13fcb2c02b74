#include "filters/shot_boundary.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <set>

#include "core/error.h"
#include "filters/verdict.h"

namespace doasido::filters {
namespace {

std::vector<double> DoubleArray(const Json& j, const char* key) {
  if (!j.contains(key) || !j.at(key).is_array()) {
    throw Error("bad_measurements", "missing per-frame array", {.field = key});
  }
  return j.at(key).get<std::vector<double>>();
}

}  // namespace

Json ToJson(const ShotSignals& s) {
  return Json{{"delta_hue", s.delta_hue},
              {"delta_sat", s.delta_sat},
              {"delta_lum", s.delta_lum},
              {"hash_distance", s.hash_distance},
              {"histogram_correlation", s.histogram_correlation},
              {"mean_intensity", s.mean_intensity},
              {"histogram_correlation_long", s.histogram_correlation_long},
              {"changed_fraction_long", s.changed_fraction_long},
              {"blend_changed", s.blend_changed},
              {"blend_unexplained", s.blend_unexplained},
              {"long_window", s.long_window},
              {"blend_step", s.blend_step}};
}

ShotSignals ShotSignalsFromJson(const Json& j) {
  ShotSignals s;
  s.delta_hue = DoubleArray(j, "delta_hue");
  s.delta_sat = DoubleArray(j, "delta_sat");
  s.delta_lum = DoubleArray(j, "delta_lum");
  s.hash_distance = DoubleArray(j, "hash_distance");
  s.histogram_correlation = DoubleArray(j, "histogram_correlation");
  s.mean_intensity = DoubleArray(j, "mean_intensity");
  s.histogram_correlation_long = DoubleArray(j, "histogram_correlation_long");
  s.changed_fraction_long = DoubleArray(j, "changed_fraction_long");
  s.long_window = j.value("long_window", 15);
  if (j.contains("blend_changed") || j.contains("blend_unexplained")) {
    s.blend_changed = DoubleArray(j, "blend_changed");
    s.blend_unexplained = DoubleArray(j, "blend_unexplained");
  }
  s.blend_step = j.value("blend_step", 3);
  const size_t n = s.delta_hue.size();
  if (s.delta_sat.size() != n || s.delta_lum.size() != n || s.hash_distance.size() != n ||
      s.histogram_correlation.size() != n || s.mean_intensity.size() != n ||
      s.histogram_correlation_long.size() != n || s.changed_fraction_long.size() != n ||
      s.blend_changed.size() != s.blend_unexplained.size() ||
      (!s.blend_changed.empty() && s.blend_changed.size() != n)) {
    throw Error("bad_measurements", "per-frame arrays differ in length",
                {.field = "shot_boundary"});
  }
  return s;
}

cv::Mat ShotSignalExtractor::Hash(const cv::Mat& gray) const {
  const int side = config_.hash_size * config_.hash_lowpass;
  cv::Mat small;
  cv::resize(gray, small, cv::Size(side, side), 0, 0, cv::INTER_AREA);
  double max_value = 0;
  cv::minMaxLoc(small, nullptr, &max_value);
  if (max_value == 0) max_value = 1;
  cv::Mat f;
  small.convertTo(f, CV_32F);
  // Divide in float32 as numpy does (float32 image / integer maximum).
  f /= static_cast<float>(max_value);
  cv::Mat dct;
  cv::dct(f, dct);
  cv::Mat low = dct(cv::Rect(0, 0, config_.hash_size, config_.hash_size)).clone();
  std::vector<float> values(low.begin<float>(), low.end<float>());
  const size_t n = values.size();
  std::nth_element(values.begin(), values.begin() + n / 2, values.end());
  float median = values[n / 2];
  if (n % 2 == 0) {
    const float below = *std::max_element(values.begin(), values.begin() + n / 2);
    median = (below + median) / 2.0f;
  }
  return low > median;
}

void ShotSignalExtractor::Begin(const VideoGeometry& geometry) {
  const double fps = geometry.fps > 0 ? geometry.fps : 30.0;
  signals_.long_window = std::max(2, static_cast<int>(std::lround(config_.long_window_s * fps)));
  signals_.blend_step = std::max(1, config_.blend_step);
}

void Luma(const cv::Mat& bgr, cv::Mat* y) {
  // OpenCV's RGB2Y coefficients (0.114, 0.587, 0.299 of 2^14) and rounding.
  constexpr int kB = 1868, kG = 9617, kR = 4899, kHalf = 1 << 13, kShift = 14;
  y->create(bgr.size(), CV_8U);
  for (int r = 0; r < bgr.rows; ++r) {
    const std::uint8_t* in = bgr.ptr<std::uint8_t>(r);
    std::uint8_t* out = y->ptr<std::uint8_t>(r);
    for (int c = 0; c < bgr.cols; ++c, in += 3) {
      out[c] = static_cast<std::uint8_t>((in[0] * kB + in[1] * kG + in[2] * kR + kHalf) >> kShift);
    }
  }
}

void ShotSignalExtractor::Consume(FrameContext& context) {
  const cv::Mat& bgr = context.frame->bgr;
  ColourSignals(bgr);
  HashSignal(context.gray);
  HistogramSignals(bgr);
  ChangedLongSignal(context.gray);
  BlendSignal();
}

// ContentDetector's inputs: the mean of all B, G, R values and the mean
// absolute change of H, S and V.
void ShotSignalExtractor::ColourSignals(const cv::Mat& bgr) {
  const double pixels = static_cast<double>(bgr.rows) * bgr.cols;
  // One channel's sum of every byte: the same exact integer as the three
  // channel sums added, summed at vector width.
  const double sum = bgr.isContinuous() ? cv::sum(bgr.reshape(1))[0] : [&bgr] {
    const cv::Scalar s = cv::sum(bgr);
    return s[0] + s[1] + s[2];
  }();
  signals_.mean_intensity.push_back(sum / (pixels * 3.0));

  cv::cvtColor(bgr, hsv_, cv::COLOR_BGR2HSV);
  if (prev_hsv_.empty()) {
    signals_.delta_hue.push_back(0);
    signals_.delta_sat.push_back(0);
    signals_.delta_lum.push_back(0);
  } else {
    cv::absdiff(hsv_, prev_hsv_, diff_);
    const cv::Scalar d = cv::sum(diff_);  // exact integer sums per channel
    signals_.delta_hue.push_back(d[0] / pixels);
    signals_.delta_sat.push_back(d[1] / pixels);
    signals_.delta_lum.push_back(d[2] / pixels);
  }
  std::swap(hsv_, prev_hsv_);
}

// HashDetector's: the share of perceptual-hash bits that changed.
void ShotSignalExtractor::HashSignal(const cv::Mat& gray) {
  cv::Mat hash = Hash(gray);
  if (prev_hash_.empty()) {
    signals_.hash_distance.push_back(0);
  } else {
    cv::Mat differ = hash != prev_hash_;
    signals_.hash_distance.push_back(static_cast<double>(cv::countNonZero(differ)) /
                                     (config_.hash_size * config_.hash_size));
  }
  prev_hash_ = hash;
}

// HistogramDetector's: the correlation of consecutive Y histograms, and the
// same over the long window.
void ShotSignalExtractor::HistogramSignals(const cv::Mat& bgr) {
  Luma(bgr, &luma_);
  cv::Mat hist;
  const int channels[] = {0};
  const int bins[] = {config_.histogram_bins};
  const float range[] = {0, 256};
  const float* ranges[] = {range};
  cv::calcHist(&luma_, 1, channels, cv::Mat(), hist, 1, bins, ranges);
  cv::normalize(hist, hist);
  if (prev_hist_.empty()) {
    signals_.histogram_correlation.push_back(1.0);
  } else {
    signals_.histogram_correlation.push_back(cv::compareHist(prev_hist_, hist, cv::HISTCMP_CORREL));
  }
  prev_hist_ = hist;
  if (static_cast<int>(hist_window_.size()) == signals_.long_window) {
    signals_.histogram_correlation_long.push_back(
        cv::compareHist(hist_window_.front(), hist, cv::HISTCMP_CORREL));
    hist_window_.pop_front();
  } else {
    signals_.histogram_correlation_long.push_back(1.0);
  }
  hist_window_.push_back(hist);
}

// The share of pixels that changed by more than 25 grey levels over the
// long window.
void ShotSignalExtractor::ChangedLongSignal(const cv::Mat& gray) {
  const double pixels = static_cast<double>(gray.rows) * gray.cols;
  if (static_cast<int>(gray_window_.size()) == signals_.long_window) {
    cv::absdiff(gray, gray_window_.front(), diff_);
    signals_.changed_fraction_long.push_back(cv::countNonZero(diff_ > 25) / pixels);
    gray_window_.pop_front();
  } else {
    signals_.changed_fraction_long.push_back(0.0);
  }
  gray_window_.push_back(gray.clone());
}

// The linear-blend test of the frame blend_step frames back (BlendCuts).
void ShotSignalExtractor::BlendSignal() {
  const int step = signals_.blend_step;
  blend_window_.push_back(gray_window_.back());
  if (static_cast<int>(blend_window_.size()) > 2 * step + 1) blend_window_.pop_front();
  if (static_cast<int>(blend_window_.size()) < 2 * step + 1) {
    signals_.blend_changed.push_back(0.0);
    signals_.blend_unexplained.push_back(1.0);
    return;
  }
  const cv::Mat& before = blend_window_.front();
  const cv::Mat& after = blend_window_.back();
  const double pixels = static_cast<double>(after.rows) * after.cols;
  // In 16-bit integers, doubled so that the average stays exact:
  // |2 mid - (before + after)| <= 2 tolerance |after - before|.
  cv::add(before, after, blend_sum_, cv::noArray(), CV_16S);
  blend_window_[step].convertTo(blend_mid_, CV_16S, 2.0);
  cv::absdiff(blend_mid_, blend_sum_, blend_mid_);
  cv::absdiff(after, before, diff_);
  diff_.convertTo(blend_diff_, CV_16S, 2.0 * config_.blend_tolerance);
  const cv::Mat changed = diff_ > config_.blend_change_level;
  const double changed_pixels = cv::countNonZero(changed);
  const double explained_pixels = cv::countNonZero(changed & (blend_mid_ <= blend_diff_));
  signals_.blend_changed.push_back(changed_pixels / pixels);
  signals_.blend_unexplained.push_back(
      changed_pixels > 0 ? 1.0 - explained_pixels / changed_pixels : 1.0);
}

std::vector<double> ContentScores(const ShotSignals& s, const ShotBoundaryConfig& c) {
  const double weight_sum =
      std::abs(c.weight_hue) + std::abs(c.weight_sat) + std::abs(c.weight_lum);
  std::vector<double> scores(s.delta_hue.size(), 0.0);
  if (weight_sum <= 0) return scores;
  for (size_t i = 0; i < scores.size(); ++i) {
    // Same summation order as PySceneDetect, so scores agree to the last bit.
    double sum = 0;
    sum += s.delta_hue[i] * c.weight_hue;
    sum += s.delta_sat[i] * c.weight_sat;
    sum += s.delta_lum[i] * c.weight_lum;
    sum += 0.0;  // edges
    scores[i] = sum / weight_sum;
  }
  return scores;
}

std::vector<std::int64_t> ContentCuts(const std::vector<double>& scores, double threshold,
                                      int min_scene_len) {
  std::vector<std::int64_t> cuts;
  if (min_scene_len <= 0) {
    for (size_t i = 0; i < scores.size(); ++i) {
      if (scores[i] >= threshold) cuts.push_back(static_cast<std::int64_t>(i));
    }
    return cuts;
  }
  std::int64_t last_above = 0;
  bool merge_enabled = false, merging = false;
  std::int64_t merge_start = 0;
  for (size_t k = 0; k < scores.size(); ++k) {
    const auto i = static_cast<std::int64_t>(k);
    const bool above = scores[k] >= threshold;
    const bool long_enough = (i - last_above) >= min_scene_len;
    if (above) last_above = i;
    if (merging) {
      if (long_enough && !above && (last_above - merge_start) >= min_scene_len) {
        merging = false;
        cuts.push_back(last_above);
      }
      continue;
    }
    if (!above) continue;
    if (long_enough) {
      merge_enabled = true;
      cuts.push_back(i);
      continue;
    }
    if (merge_enabled) {
      merging = true;
      merge_start = i;
    }
  }
  return cuts;
}

std::vector<std::int64_t> AdaptiveCuts(const std::vector<double>& scores, double adaptive_threshold,
                                       double min_content_val, int window_width,
                                       int min_scene_len) {
  std::vector<std::int64_t> cuts;
  if (window_width < 1) {
    throw Error("bad_config", "window_width must be at least 1",
                {.field = "shot_boundary.window_width"});
  }
  const auto n = static_cast<std::int64_t>(scores.size());
  std::int64_t last_cut = 0;
  for (std::int64_t i = 2 * window_width; i < n; ++i) {
    const std::int64_t target = i - window_width;
    double sum = 0;
    for (std::int64_t j = i - 2 * window_width; j <= i; ++j) {
      if (j != target) sum += scores[j];
    }
    const double average = sum / (2.0 * window_width);
    const double score = scores[target];
    double ratio = 0;
    if (std::abs(average) >= 0.00001) {
      ratio = std::min(score / average, 255.0);
    } else if (score >= min_content_val) {
      ratio = 255.0;
    }
    const bool threshold_met = ratio >= adaptive_threshold && score >= min_content_val;
    const bool long_enough = (i - last_cut) >= min_scene_len;
    if (threshold_met && long_enough) {
      last_cut = target;
      cuts.push_back(target);
    }
  }
  return cuts;
}

std::vector<std::int64_t> HashCuts(const std::vector<double>& distance, double threshold,
                                   int min_scene_len) {
  std::vector<std::int64_t> cuts;
  std::int64_t last_cut = 0;
  for (size_t k = 1; k < distance.size(); ++k) {
    const auto i = static_cast<std::int64_t>(k);
    if (distance[k] >= threshold && (i - last_cut) >= min_scene_len) {
      cuts.push_back(i);
      last_cut = i;
    }
  }
  return cuts;
}

std::vector<std::int64_t> HistogramCuts(const std::vector<double>& correlation, double threshold,
                                        int min_scene_len) {
  std::vector<std::int64_t> cuts;
  const double max_correlation = std::clamp(1.0 - threshold, 0.0, 1.0);
  std::int64_t last_cut = 0;
  for (size_t k = 1; k < correlation.size(); ++k) {
    const auto i = static_cast<std::int64_t>(k);
    if (correlation[k] <= max_correlation && (i - last_cut) >= min_scene_len) {
      cuts.push_back(i);
      last_cut = i;
    }
  }
  return cuts;
}

std::vector<std::int64_t> DissolveCuts(const std::vector<double>& changed_fraction, int long_window,
                                       double threshold, double steady, int min_scene_len) {
  std::vector<std::int64_t> cuts;
  std::int64_t last_cut = 0;
  const auto n = static_cast<std::int64_t>(changed_fraction.size());
  for (std::int64_t i = 0; i < n;) {
    if (changed_fraction[i] < threshold) {
      ++i;
      continue;
    }
    std::int64_t peak = i;
    for (; i < n && changed_fraction[i] >= threshold; ++i) {
      if (changed_fraction[i] > changed_fraction[peak]) peak = i;
    }
    // A transition between two steady shots, not a scene that keeps
    // changing (a moving camera): the unsteady stretch around the peak lasts
    // at most two windows (a dissolve of d frames gives d + window).
    std::int64_t left = peak, right = peak;
    while (left > 0 && changed_fraction[left - 1] > steady) --left;
    while (right + 1 < n && changed_fraction[right + 1] > steady) ++right;
    const bool transition = right - left + 1 <= 2 * static_cast<std::int64_t>(long_window);
    const std::int64_t cut = std::max<std::int64_t>(1, peak - long_window / 2);
    if (transition && cut - last_cut >= min_scene_len) {
      cuts.push_back(cut);
      last_cut = cut;
    }
  }
  return cuts;
}

std::vector<std::int64_t> BlendCuts(const std::vector<double>& changed,
                                    const std::vector<double>& unexplained, int step,
                                    double min_changed, double max_unexplained, int min_run,
                                    int min_scene_len) {
  std::vector<std::int64_t> cuts;
  const auto n = static_cast<std::int64_t>(std::min(changed.size(), unexplained.size()));
  const auto blended = [&](std::int64_t t) {
    return changed[t] >= min_changed && unexplained[t] <= max_unexplained;
  };
  std::int64_t last_cut = 0;
  for (std::int64_t t = 0; t < n;) {
    if (!blended(t)) {
      ++t;
      continue;
    }
    const std::int64_t begin = t;
    while (t < n && blended(t)) ++t;
    if (t - begin < std::max(1, min_run)) continue;
    // Entry t describes frame t - step.
    const std::int64_t cut = std::max<std::int64_t>(1, (begin + t - 1) / 2 - step);
    if (cut - last_cut >= min_scene_len) {
      cuts.push_back(cut);
      last_cut = cut;
    }
  }
  return cuts;
}

std::vector<std::int64_t> FadeCuts(const std::vector<double>& mean_intensity, double threshold,
                                   int min_scene_len, double fade_bias) {
  std::vector<std::int64_t> cuts;
  if (mean_intensity.empty()) return cuts;
  // PySceneDetect truncates the threshold to an integer.
  const double level = std::trunc(threshold);
  bool faded_out = mean_intensity[0] < level;
  std::int64_t last_fade = 0;
  std::int64_t last_cut = 0;
  for (size_t k = 1; k < mean_intensity.size(); ++k) {
    const auto i = static_cast<std::int64_t>(k);
    const bool dark = mean_intensity[k] < level;
    if (!faded_out && dark) {
      faded_out = true;
      last_fade = i;
    } else if (faded_out && !dark) {
      if (i - last_cut >= min_scene_len) {
        // The midpoint of fade-out and fade-in (skewed by the bias), rounded
        // half up: PySceneDetect's current release places the split in time
        // and rounds to the nearest frame (its goldens put testvideo's third
        // fade at 377 for a fade-out at 355 and a fade-in at 398).
        const double split =
            (static_cast<double>(i + last_fade) + fade_bias * static_cast<double>(i - last_fade)) /
            2.0;
        cuts.push_back(static_cast<std::int64_t>(std::floor(split + 0.5)));
        last_cut = i;
      }
      faded_out = false;
      last_fade = i;
    }
  }
  return cuts;
}

std::vector<std::int64_t> CutsOf(const std::string& name, const ShotSignals& s,
                                 const ShotBoundaryConfig& c) {
  if (name == "content") {
    return ContentCuts(ContentScores(s, c), c.content_threshold, c.min_scene_len);
  }
  if (name == "adaptive") {
    return AdaptiveCuts(ContentScores(s, c), c.adaptive_threshold, c.min_content_val,
                        c.window_width, c.min_scene_len);
  }
  if (name == "hash") return HashCuts(s.hash_distance, c.hash_threshold, c.min_scene_len);
  if (name == "histogram") {
    return HistogramCuts(s.histogram_correlation, c.histogram_threshold, c.min_scene_len);
  }
  if (name == "dissolve") {
    std::vector<std::int64_t> all = DissolveCuts(s.changed_fraction_long, s.long_window,
                                                 c.dissolve_threshold, c.dissolve_steady,
                                                 c.min_scene_len);
    const std::vector<std::int64_t> blends =
        BlendCuts(s.blend_changed, s.blend_unexplained, s.blend_step, c.blend_min_changed,
                  c.blend_max_unexplained, c.blend_min_run, c.min_scene_len);
    all.insert(all.end(), blends.begin(), blends.end());
    std::sort(all.begin(), all.end());
    // A hard cut also changes every pixel against the frame a window back:
    // what the long-window test sees then is the cut, not a cross-fade.
    const std::vector<std::int64_t> hard = AdaptiveCuts(
        ContentScores(s, c), c.adaptive_threshold, c.min_content_val, c.window_width, c.min_scene_len);
    auto near_hard_cut = [&](std::int64_t cut) {
      return std::any_of(hard.begin(), hard.end(), [&](std::int64_t h) {
        return std::abs(h - cut) <= std::max<std::int64_t>(s.long_window, 1);
      });
    };
    std::vector<std::int64_t> cuts;
    for (std::int64_t cut : all) {
      if (near_hard_cut(cut)) continue;
      if (cut - (cuts.empty() ? 0 : cuts.back()) >= c.min_scene_len) cuts.push_back(cut);
    }
    return cuts;
  }
  if (name == "fade") {
    return FadeCuts(s.mean_intensity, c.fade_threshold, c.min_scene_len, c.fade_bias);
  }
  throw Error("bad_config", "unknown shot detector \"" + name + "\"",
              {.field = "shot_boundary.boundary_detectors"});
}

FilterVerdict DecideShots(const Json& measurements, const ShotBoundaryConfig& config) {
  RequireAnalysis(measurements, kShotBoundaryStageName);
  const ShotSignals signals = ShotSignalsFromJson(measurements.at("signals"));
  const Json& clip = measurements.at("clip");
  const auto first = static_cast<std::int64_t>(NumberOr(clip, "first_frame", 0));
  const double fps = NumberOr(clip, "fps", 30.0);
  const auto n = static_cast<std::int64_t>(signals.mean_intensity.size());

  Json cuts_by = Json::object();
  std::set<std::int64_t> boundaries;
  for (const std::string& name : config.boundary_detectors) {
    const std::vector<std::int64_t> cuts = CutsOf(name, signals, config);
    Json absolute = Json::array();
    for (std::int64_t c : cuts) {
      absolute.push_back(first + c);
      if (c > 0 && c < n) boundaries.insert(c);
    }
    cuts_by[name] = absolute;
  }
  if (std::find(config.boundary_detectors.begin(), config.boundary_detectors.end(), "fade") !=
      config.boundary_detectors.end()) {
    const double level = std::trunc(config.fade_threshold);
    std::int64_t lead = 0, tail = n;
    while (lead < n && signals.mean_intensity[lead] < level) ++lead;
    while (tail > lead && signals.mean_intensity[tail - 1] < level) --tail;
    if (lead > 0 && lead < n) boundaries.insert(lead);
    if (tail < n && tail > 0) boundaries.insert(tail);
    cuts_by["dark_ends"] = Json::array();
    if (lead > 0) cuts_by["dark_ends"].push_back(first + lead);
    if (tail < n) cuts_by["dark_ends"].push_back(first + tail);
  }
  // Segments [start, end) between boundaries; the longest wins (earliest on ties).
  std::int64_t best_start = 0, best_end = n, start = 0;
  if (!boundaries.empty()) {
    best_end = 0;
    for (std::int64_t b : boundaries) {
      if (b - start > best_end - best_start) {
        best_start = start;
        best_end = b;
      }
      start = b;
    }
    if (n - start > best_end - best_start) {
      best_start = start;
      best_end = n;
    }
  }
  const double segment_s = static_cast<double>(best_end - best_start) / (fps > 0 ? fps : 30.0);
  FilterVerdict result;
  Json summary = {{"cuts", cuts_by},
                  {"boundaries", Json::array()},
                  {"longest_segment",
                   {{"start_frame", first + best_start},
                    {"end_frame", first + best_end - 1},
                    {"seconds", segment_s}}}};
  for (std::int64_t b : boundaries) summary["boundaries"].push_back(first + b);
  // A clip without boundaries passes whatever its length, so only clips with
  // boundaries have a thresholded score.
  summary["scores"] = Json::array();
  if (!boundaries.empty()) {
    summary["scores"].push_back(
        ScoreEntry("longest_segment_s", segment_s, false, config.min_segment_s));
  }
  if (boundaries.empty()) {
    result.verdict = Verdict::kPass;
  } else if (segment_s >= config.min_segment_s) {
    result.verdict = Verdict::kPass;
    result.reason = kReasonTrimmed;
    summary["trim"] = {{"start_frame", first + best_start}, {"end_frame", first + best_end - 1}};
  } else {
    result.verdict = Verdict::kReject;
    result.reason = kReasonShotBoundary;
  }
  result.measurements = measurements;
  result.measurements["summary"] = summary;
  return result;
}

}  // namespace doasido::filters
