#include "filters/interaction.h"

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/json_input.h"
#include "core/shell_words.h"
#include "filters/out_of_frame.h"
#include "filters/verdict.h"

namespace doasido::filters {
namespace {

// Gap between two boxes in pixels (0 when they overlap).
double BoxGap(const cv::Rect2d& a, const cv::Rect2d& b) {
  const double dx = std::max({0.0, b.x - (a.x + a.width), a.x - (b.x + b.width)});
  const double dy = std::max({0.0, b.y - (a.y + a.height), a.y - (b.y + b.height)});
  return std::hypot(dx, dy);
}

struct Component {
  cv::Rect box;
  int area = 0;
  int label = 0;
};

// The 8-connected components of `mask`, largest first, labelled in
// `labels`. Grana's block-based algorithm: the same labels and statistics
// as OpenCV's default (Spaghetti; checked on every real sample video), at
// half its cost on 256-pixel frames, where the default's statistics pass
// costs more than the labelling.
std::vector<Component> Components(const cv::Mat& mask, cv::Mat& labels) {
  cv::Mat stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S,
                                                 cv::CCL_GRANA);
  std::vector<Component> out;
  for (int i = 1; i < n; ++i) {
    out.push_back(
        {cv::Rect(stats.at<int>(i, cv::CC_STAT_LEFT), stats.at<int>(i, cv::CC_STAT_TOP),
                  stats.at<int>(i, cv::CC_STAT_WIDTH), stats.at<int>(i, cv::CC_STAT_HEIGHT)),
         stats.at<int>(i, cv::CC_STAT_AREA), i});
  }
  std::sort(out.begin(), out.end(),
            [](const Component& a, const Component& b) { return a.area > b.area; });
  return out;
}

// The steps of BuiltinHandObjectDetector::Consume.

// Skin-coloured pixels (a YCrCb box), opened then closed to drop specks
// and fill small holes.
cv::Mat SkinMask(const cv::Mat& bgr, const BuiltinDetectorConfig& config) {
  cv::Mat ycrcb, skin;
  cv::cvtColor(bgr, ycrcb, cv::COLOR_BGR2YCrCb);
  cv::inRange(ycrcb, cv::Scalar(config.y_min, config.cr_min, config.cb_min),
              cv::Scalar(255, config.cr_max, config.cb_max), skin);
  cv::morphologyEx(skin, skin, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
  cv::morphologyEx(skin, skin, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
  return skin;
}

// Pixels that changed since `old_gray`. When much of the picture changed,
// a global shift (camera pan) is estimated at half size by phase
// correlation and undone in `old_gray` and `old_skin`, so that only things
// that moved in the scene count as motion.
cv::Mat SceneMotion(const cv::Mat& gray, cv::Mat& old_gray, cv::Mat& old_skin,
                    const BuiltinDetectorConfig& config) {
  const double frame_area = static_cast<double>(gray.rows) * gray.cols;
  cv::Mat diff, motion;
  cv::absdiff(gray, old_gray, diff);
  motion = diff > config.motion_threshold;
  if (config.compensate_camera &&
      cv::countNonZero(motion) > config.global_motion_fraction * frame_area) {
    cv::Mat a, b;
    cv::resize(old_gray, a, {}, 0.5, 0.5, cv::INTER_AREA);
    cv::resize(gray, b, {}, 0.5, 0.5, cv::INTER_AREA);
    a.convertTo(a, CV_32F);
    b.convertTo(b, CV_32F);
    double response = 0;
    const cv::Point2d shift = cv::phaseCorrelate(a, b, cv::noArray(), &response) * 2.0;
    if (response > 0.05 && std::hypot(shift.x, shift.y) > 0.5) {
      const cv::Matx23d m(1, 0, shift.x, 0, 1, shift.y);
      cv::warpAffine(old_gray, old_gray, m, gray.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
      cv::warpAffine(old_skin, old_skin, m, gray.size(), cv::INTER_NEAREST, cv::BORDER_REPLICATE);
      cv::absdiff(gray, old_gray, diff);
      motion = diff > config.motion_threshold;
    }
  }
  cv::morphologyEx(motion, motion, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
  return motion;
}

// Hands: skin regions of plausible size of which enough moved, each boxed
// by the part that moved (hands move more than the arms and clothes a skin
// region often includes), grown a little.
std::vector<cv::Rect2d> MovingHands(const cv::Mat& skin, const cv::Mat& motion,
                                    const BuiltinDetectorConfig& config, double frame_area) {
  std::vector<cv::Rect2d> hands;
  const cv::Mat moving_skin = motion & skin;
  // A hand is a component of at least min_hand_area of the frame of which
  // at least min_hand_motion moved: with fewer moving skin pixels in the
  // whole frame than that (a still or hand-less picture) none can be, and
  // the components are not labelled (the 0.999 keeps rounding out of it).
  if (config.min_hand_motion > 0 &&
      cv::countNonZero(moving_skin) <
          0.999 * config.min_hand_motion * config.min_hand_area * frame_area) {
    return hands;
  }
  cv::Mat labels;
  const std::vector<Component> skin_parts = Components(skin, labels);
  for (const Component& c : skin_parts) {
    if (static_cast<int>(hands.size()) >= config.max_hands) break;
    if (c.area < config.min_hand_area * frame_area) break;  // sorted by area
    if (c.area > config.max_hand_area * frame_area) continue;
    const cv::Mat mine = labels(c.box) == c.label;
    const cv::Mat moved_here = moving_skin(c.box) & mine;
    const int moved = cv::countNonZero(moved_here);
    if (moved < config.min_hand_motion * c.area) continue;
    // The mask's own bounding box: the same box as of its non-zero points.
    cv::Rect part = cv::boundingRect(moved_here) + c.box.tl();
    const int grow = std::max(2, part.width / 8);
    part = cv::Rect(part.x - grow, part.y - grow, part.width + 2 * grow, part.height + 2 * grow) &
           c.box;
    hands.emplace_back(part.x, part.y, part.width, part.height);
  }
  return hands;
}

// Objects: motion that is neither skin now nor where skin was (`any_skin`),
// within `reach` pixels of a hand; at most two.
std::vector<cv::Rect2d> ObjectsTouchingHands(const cv::Mat& motion, const cv::Mat& any_skin,
                                             const std::vector<cv::Rect2d>& hands, double reach,
                                             const BuiltinDetectorConfig& config,
                                             double frame_area) {
  std::vector<cv::Rect2d> objects;
  cv::Mat near_skin;
  cv::dilate(any_skin, near_skin, cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}), {-1, -1},
             2);
  cv::Mat other = motion & ~near_skin;
  cv::dilate(other, other, cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
  // No component can reach min_object_area when all of them together do
  // not: no labelling then.
  if (cv::countNonZero(other) < 0.999 * config.min_object_area * frame_area) return objects;
  cv::Mat object_labels;
  for (const Component& c : Components(other, object_labels)) {
    if (c.area < config.min_object_area * frame_area) break;
    const cv::Rect2d box(c.box.x, c.box.y, c.box.width, c.box.height);
    bool next_to_hand = false;
    for (const cv::Rect2d& h : hands) next_to_hand |= BoxGap(h, box) <= reach;
    if (next_to_hand) objects.push_back(box);
    if (objects.size() >= 2) break;
  }
  return objects;
}

// A box found at `scale` of the frame as a detection in frame pixels.
Detection BoxDetection(const cv::Rect2d& b, double scale, std::int64_t frame,
                       const std::string& kind, int contact) {
  Detection d;
  d.frame = frame;
  d.kind = kind;
  d.x1 = b.x * scale;
  d.y1 = b.y * scale;
  d.x2 = (b.x + b.width) * scale;
  d.y2 = (b.y + b.height) * scale;
  d.score = 1.0;
  d.contact_state = contact;
  d.source = "detector:builtin";
  return d;
}

}  // namespace

void BuiltinHandObjectDetector::Consume(FrameContext& context) {
  const cv::Mat& gray = context.gray;
  const double frame_area = static_cast<double>(gray.rows) * gray.cols;
  const cv::Mat skin = SkinMask(context.frame->bgr, config_);
  FrameBoxes found;
  found.known = true;
  if (static_cast<int>(grays_.size()) >= config_.motion_gap) {
    cv::Mat old_gray = grays_.front();
    cv::Mat old_skin = skins_.front();
    const cv::Mat motion = SceneMotion(gray, old_gray, old_skin, config_);
    found.hands = MovingHands(skin, motion, config_, frame_area);
    const bool seen = !found.hands.empty();
    if (!seen && context.ordinal - last_seen_ <= config_.hold_frames) {
      found.hands = last_.hands;  // a still hand is still there
    }
    const double reach = config_.contact_distance * std::hypot(gray.cols, gray.rows);
    if (!found.hands.empty()) {
      found.objects = ObjectsTouchingHands(motion, skin | old_skin, found.hands, reach, config_,
                                           frame_area);
    }
    for (const cv::Rect2d& h : found.hands) {
      bool contact = false;
      for (const cv::Rect2d& o : found.objects) contact |= BoxGap(h, o) <= reach;
      found.hand_contact.push_back(contact ? 3 : 0);
    }
    if (seen) {
      last_seen_ = context.ordinal;
      last_ = found;
    }
  }
  grays_.push_back(gray.clone());
  skins_.push_back(skin);
  while (static_cast<int>(grays_.size()) > config_.motion_gap) {
    grays_.pop_front();
    skins_.pop_front();
  }
  const double s = geometry_.downscale;
  for (size_t i = 0; i < found.hands.size(); ++i) {
    detections_.push_back(BoxDetection(found.hands[i], s, context.frame->index, "hand",
                                       found.hand_contact[i]));
  }
  for (const cv::Rect2d& o : found.objects) {
    detections_.push_back(BoxDetection(o, s, context.frame->index, "object", -1));
  }
  context.boxes = found;
}

Json ToJson(const InteractionSignals& s) {
  return Json{{"covered", s.covered}, {"hands", s.hands},           {"objects", s.objects},
              {"contact", s.contact}, {"in_contact", s.in_contact}};
}

InteractionSignals InteractionSignalsFromJson(const Json& j) {
  InteractionSignals s;
  s.covered = IntArray(j, "covered");
  s.hands = IntArray(j, "hands");
  s.objects = IntArray(j, "objects");
  s.contact = IntArray(j, "contact");
  if (j.contains("in_contact")) s.in_contact = IntArray(j, "in_contact");
  const size_t n = s.covered.size();
  if (s.hands.size() != n || s.objects.size() != n || s.contact.size() != n ||
      (!s.in_contact.empty() && s.in_contact.size() != n)) {
    throw Error("bad_measurements", "per-frame arrays differ in length", {.field = "interaction"});
  }
  return s;
}

void InteractionExtractor::Consume(FrameContext& context) {
  const FrameBoxes& b = context.boxes;
  int mask = 0, touching = 0;
  for (size_t i = 0; i < b.hands.size(); ++i) {
    const int state = i < b.hand_contact.size() ? b.hand_contact[i] : -1;
    if (state >= 0 && state <= 4) {
      mask |= 1 << state;
      touching += state == 3 || state == 4;
    } else if (TouchedObject(b.hands[i], b.objects) >= 0) {
      mask |= 1 << 3;  // unknown state, object at the hand: a portable object
      ++touching;
    } else {
      mask |= 1 << 5;
    }
  }
  signals_.covered.push_back(b.known ? 1 : 0);
  signals_.hands.push_back(static_cast<int>(b.hands.size()));
  signals_.objects.push_back(static_cast<int>(b.objects.size()));
  signals_.contact.push_back(mask);
  signals_.in_contact.push_back(touching);
}

double InteractionFraction(const InteractionSignals& s, const std::vector<int>& contact_states,
                           std::int64_t first, std::int64_t last) {
  int wanted = 0;
  for (int state : contact_states) {
    if (state >= 0 && state <= 5) wanted |= 1 << state;
  }
  size_t covered = 0, interacting = 0;
  last = std::min<std::int64_t>(last, static_cast<std::int64_t>(s.covered.size()) - 1);
  for (std::int64_t i = std::max<std::int64_t>(0, first); i <= last; ++i) {
    if (!s.covered[i]) continue;
    ++covered;
    if (s.contact[i] & wanted) ++interacting;
  }
  return covered > 0 ? static_cast<double>(interacting) / static_cast<double>(covered) : 0.0;
}

FilterVerdict DecideInteraction(const Json& measurements, const InteractionConfig& c) {
  RequireAnalysis(measurements, kInteractionStageName);
  const InteractionSignals s = InteractionSignalsFromJson(measurements.at("signals"));
  const ShotSpan span = SpanOf(measurements, static_cast<std::int64_t>(s.covered.size()));
  size_t covered = 0, with_hands = 0, two_hands = 0;
  for (std::int64_t i = span.first; i <= span.last; ++i) {
    covered += s.covered[i] != 0;
    with_hands += (s.covered[i] && s.hands[i] > 0) ? 1 : 0;
    two_hands += s.covered[i] && !s.in_contact.empty() && s.in_contact[i] >= 2;
  }
  const double n = std::max<double>(1.0, static_cast<double>(span.last - span.first + 1));
  const double covered_fraction = static_cast<double>(covered) / n;
  const double fraction = InteractionFraction(s, c.contact_states, span.first, span.last);
  FilterVerdict result;
  result.measurements = measurements;
  result.measurements["summary"] = {
      {"covered_fraction", covered_fraction},
      {"hand_fraction", covered > 0 ? static_cast<double>(with_hands) / covered : 0.0},
      {"interaction_fraction", fraction},
      // Covered frames where both hands touch an object (bimanual clips).
      {"two_hand_fraction", s.in_contact.empty() ? Json() : Json(covered > 0 ? double(two_hands) / covered : 0.0)},
      {"scores",
       {ScoreEntry("interaction_fraction", fraction, false, c.min_interaction_fraction),
        ScoreEntry("covered_fraction", covered_fraction, false, c.min_covered_fraction)}}};
  if (covered_fraction < c.min_covered_fraction) {
    SetVerdict(result, Verdict::kFlag, kReasonNoDetections);
  } else if (fraction < c.min_interaction_fraction) {
    SetVerdict(result, Verdict::kReject, kReasonNoInteraction);
  }
  return result;
}

std::vector<Detection> ReadDetectorOutput(const std::filesystem::path& path, double min_score,
                                          const std::string& source) {
  std::ifstream in(path);
  if (!in) {
    throw Error("bad_detections", "cannot open detector output", {.file = path.string()});
  }
  std::vector<Detection> out;
  std::string line;
  long number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const ErrorSite site{.file = path.string(), .line = number};
    Json row;
    try {
      row = ParseJsonInput(line, site, {.max_depth = 8, .max_bytes = 16u << 20});
    } catch (const Error& e) {
      throw Error("bad_detections", e.code() + ": " + e.message(), site);
    }
    if (!row.is_object() || !row.contains("frame") || !row.at("frame").is_number_integer()) {
      throw Error("bad_detections", "row lacks an integer \"frame\"",
                  {.file = site.file, .line = number, .field = "frame"});
    }
    const auto frame = row.at("frame").get<std::int64_t>();
    for (const char* key : {"hand_dets", "obj_dets"}) {
      if (!row.contains(key) || row.at(key).is_null()) continue;
      const bool hands = std::string(key) == "hand_dets";
      if (!row.at(key).is_array()) {
        throw Error("bad_detections", "not an array",
                    {.file = site.file, .line = number, .field = key});
      }
      for (const Json& det : row.at(key)) {
        const size_t need = hands ? 10 : 5;
        if (!det.is_array() || det.size() < need) {
          throw Error("bad_detections", "a detection needs " + std::to_string(need) + " numbers",
                      {.file = site.file, .line = number, .field = key});
        }
        std::vector<double> v;
        for (const Json& x : det) {
          if (!x.is_number()) {
            throw Error("bad_detections", "a detection value is not a number",
                        {.file = site.file, .line = number, .field = key});
          }
          v.push_back(x.get<double>());
        }
        if (v[4] < min_score) continue;
        if (!(v[2] > v[0]) || !(v[3] > v[1])) {
          throw Error("bad_detections", "box has x2 <= x1 or y2 <= y1",
                      {.file = site.file, .line = number, .field = key});
        }
        Detection d;
        d.frame = frame;
        d.kind = hands ? "hand" : "object";
        d.x1 = v[0];
        d.y1 = v[1];
        d.x2 = v[2];
        d.y2 = v[3];
        d.score = v[4];
        if (hands) {
          d.contact_state = static_cast<int>(v[5]);
          d.dx = v[6];
          d.dy = v[7];
          d.magnitude = v[8];
          d.hand_side = static_cast<int>(v[9]);
        }
        d.source = source;
        out.push_back(d);
      }
    }
  }
  return out;
}

std::vector<Detection> RunExternalDetector(const ExternalDetectorConfig& config,
                                           const std::filesystem::path& video,
                                           std::int64_t first_frame, std::int64_t last_frame,
                                           const std::filesystem::path& output,
                                           const std::string& clip) {
  std::string command = config.command;
  ReplaceAll(command, "{video}", ShellQuote(std::filesystem::absolute(video).string()));
  ReplaceAll(command, "{first_frame}", ShellQuote(std::to_string(first_frame)));
  ReplaceAll(command, "{last_frame}", ShellQuote(std::to_string(last_frame)));
  ReplaceAll(command, "{output}", ShellQuote(output.string()));
  std::error_code ignored;
  std::filesystem::remove(output, ignored);
  const int status = std::system(command.c_str());
  const ErrorSite site{.clip = clip, .file = video.string(), .field = "command"};
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw Error("detector_failed",
                "external detector failed (status " + std::to_string(status) + "): " + command,
                site);
  }
  if (!std::filesystem::exists(output)) {
    throw Error("detector_failed", "external detector wrote no output file: " + command, site);
  }
  return ReadDetectorOutput(output, config.min_score, "detector:external");
}

}  // namespace doasido::filters
