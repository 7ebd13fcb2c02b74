#include "reports/thumbnails.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <set>

#include "core/error.h"
#include "filters/kept_shot.h"
#include "video/video_decoder.h"
#include "filters/activity.h"
#include "filters/camera_motion.h"
#include "filters/out_of_frame.h"
#include "filters/shot_boundary.h"

namespace doasido::reports {
namespace {

const cv::Scalar kHandColour(60, 200, 60);      // BGR green
const cv::Scalar kObjectColour(0, 150, 255);    // BGR orange
const cv::Scalar kHighlight(255, 0, 255);       // magenta
const cv::Scalar kCutColour(0, 0, 255);         // red
const cv::Scalar kArrowColour(0, 255, 255);     // yellow

std::string ClipLabel(const ClipRecord& clip) {
  return clip.external_id.empty() ? "clip " + std::to_string(clip.id) : clip.external_id;
}

// A panel to be drawn: a file frame and what to put on it.
struct Panel {
  std::int64_t frame = 0;
  std::string label;
  cv::Mat image;  // filled by decoding, then drawn on
};

void PutLabel(cv::Mat& image, const std::string& text, cv::Point at, double scale = 0.4) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
  cv::rectangle(image, {at.x - 1, at.y - size.height - 2}, {at.x + size.width + 1, at.y + baseline},
                cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);
}

// Boxes on `frame`, or on the nearest frame with boxes within `window`.
std::vector<Detection> BoxesNear(const std::vector<Detection>& detections, std::int64_t frame,
                                 int window, std::int64_t* from_frame) {
  std::int64_t best = -1;
  std::int64_t best_gap = window + 1;
  for (const auto& d : detections) {
    const std::int64_t gap = std::llabs(d.frame - frame);
    if (gap < best_gap || (gap == best_gap && d.frame < best)) best_gap = gap, best = d.frame;
  }
  std::vector<Detection> out;
  if (best < 0) return out;
  for (const auto& d : detections) {
    if (d.frame == best) out.push_back(d);
  }
  *from_frame = best;
  return out;
}

cv::Mat Compose(std::vector<Panel>& panels, int height, const std::vector<bool>& cut_after) {
  std::vector<cv::Mat> scaled;
  int width = 0;
  for (auto& p : panels) {
    const double s = static_cast<double>(height) / p.image.rows;
    cv::Mat r;
    cv::resize(p.image, r, cv::Size(std::max(1, static_cast<int>(std::lround(p.image.cols * s))),
                                    height), 0, 0, cv::INTER_AREA);
    PutLabel(r, p.label, {3, height - 5});
    width += r.cols;
    scaled.push_back(r);
  }
  const int gap = 4;
  width += gap * static_cast<int>(scaled.size() - 1);
  cv::Mat out(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  int x = 0;
  for (size_t i = 0; i < scaled.size(); ++i) {
    scaled[i].copyTo(out(cv::Rect(x, 0, scaled[i].cols, height)));
    x += scaled[i].cols;
    if (i + 1 < scaled.size()) {
      // A red bar marks a cut between two panels; white separates others.
      const cv::Scalar colour = cut_after[i] ? kCutColour : cv::Scalar(255, 255, 255);
      cv::rectangle(out, cv::Rect(x, 0, gap, height), colour, cv::FILLED);
      x += gap;
    }
  }
  return out;
}

}  // namespace

std::string OverlayKind(const std::string& stage, const std::string& reason) {
  auto has = [&](const char* word) {
    return stage.find(word) != std::string::npos || reason.find(word) != std::string::npos;
  };
  if (has(filters::kShotBoundaryStageName) || has("cut")) return "cut";
  if (has(filters::kCameraMotionStageName)) return "motion";
  if (has(filters::kOutOfFrameStageName)) return "border";
  if (has(filters::kActivityStageName)) return "activity";
  return "boxes";
}

bool TouchesBorder(const Detection& d, int width, int height, double margin) {
  return d.x1 <= margin || d.y1 <= margin || d.x2 >= width - margin || d.y2 >= height - margin;
}

void DrawDetections(cv::Mat& image, const std::vector<Detection>& boxes, double scale,
                    int highlight) {
  static const char kContact[] = "NSOPF";
  for (size_t i = 0; i < boxes.size(); ++i) {
    const Detection& d = boxes[i];
    const bool hand = d.kind == "hand";
    const bool hi = static_cast<int>(i) == highlight;
    const cv::Point p1(static_cast<int>(std::lround(d.x1 * scale)),
                       static_cast<int>(std::lround(d.y1 * scale)));
    const cv::Point p2(static_cast<int>(std::lround(d.x2 * scale)) - 1,
                       static_cast<int>(std::lround(d.y2 * scale)) - 1);
    cv::rectangle(image, p1, p2, hi ? kHighlight : (hand ? kHandColour : kObjectColour),
                  hi ? 3 : 2);
    std::string label = hand ? (d.hand_side == 0 ? "L" : d.hand_side == 1 ? "R" : "H") : "obj";
    if (hand && d.contact_state >= 0 && d.contact_state <= 4) {
      label += std::string(" ") + kContact[d.contact_state];
    }
    PutLabel(image, label, {std::max(p1.x, 0) + 2, std::max(p1.y, 0) + 12}, 0.35);
  }
}

std::vector<MotionVector> TrackMotion(const cv::Mat& a, const cv::Mat& b, int max_corners) {
  cv::Mat ga, gb;
  if (a.channels() == 3) cv::cvtColor(a, ga, cv::COLOR_BGR2GRAY); else ga = a;
  if (b.channels() == 3) cv::cvtColor(b, gb, cv::COLOR_BGR2GRAY); else gb = b;
  std::vector<cv::Point2f> p0;
  cv::goodFeaturesToTrack(ga, p0, max_corners, 0.01, 7);
  std::vector<MotionVector> out;
  if (p0.empty()) return out;
  std::vector<cv::Point2f> p1, back;
  std::vector<unsigned char> ok1, ok2;
  std::vector<float> err;
  const cv::Size window(21, 21);
  cv::calcOpticalFlowPyrLK(ga, gb, p0, p1, ok1, err, window, 3);
  cv::calcOpticalFlowPyrLK(gb, ga, p1, back, ok2, err, window, 3);
  for (size_t i = 0; i < p0.size(); ++i) {
    if (!ok1[i] || !ok2[i]) continue;
    const cv::Point2f d = back[i] - p0[i];
    if (d.dot(d) > 1.0f) continue;
    out.push_back({p0[i], p1[i]});
  }
  return out;
}

std::string Base64(const std::vector<unsigned char>& bytes) {
  static const char kTable[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (bytes[i] << 16) | (bytes[i + 1] << 8) | bytes[i + 2];
    out += kTable[(v >> 18) & 63];
    out += kTable[(v >> 12) & 63];
    out += kTable[(v >> 6) & 63];
    out += kTable[v & 63];
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = bytes[i] << 16;
    out += kTable[(v >> 18) & 63];
    out += kTable[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (bytes[i] << 16) | (bytes[i + 1] << 8);
    out += kTable[(v >> 18) & 63];
    out += kTable[(v >> 12) & 63];
    out += kTable[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

namespace {

// The panels of a strip and how to draw them.
struct PanelPlan {
  std::vector<Panel> panels;
  std::vector<bool> cut_after;  // a cut mark after panel i
  int highlight_panel = -1;     // the panel whose border_box touches the border
  Detection border_box;
  std::string caption;
};

// The clip's frames [first, last] in the file, and its middle.
struct ClipSpan {
  std::int64_t first = 0, last = 0, mid = 0;
};

ClipSpan SpanOf(const ClipRecord& c, const VideoDecoder& decoder) {
  const VideoGeometry& g = decoder.geometry();
  ClipSpan s;
  s.first = decoder.first_frame();
  s.last = -1;
  if (c.end_frame) s.last = *c.end_frame;
  else if (c.end_s && g.fps > 0) s.last = static_cast<std::int64_t>(std::lround(*c.end_s * g.fps));
  else if (g.declared_frames > 0) s.last = g.declared_frames - 1;
  if (s.last < s.first) s.last = s.first + std::max<std::int64_t>(1, std::llround(g.fps));
  s.mid = s.first + (s.last - s.first) / 2;
  return s;
}

// The frames either side of the first two cuts the shot filter found.
void PlanCuts(const ThumbnailRequest& request, const ClipSpan& span, PanelPlan& plan) {
  std::vector<std::int64_t> cuts;
  for (std::int64_t b : filters::KeptShotFromSummary(request.shot_summary).boundaries) {
    if (b > span.first) cuts.push_back(b);
  }
  for (size_t i = 0; i < cuts.size() && i < 2; ++i) {
    plan.panels.push_back({cuts[i] - 1, "f" + std::to_string(cuts[i] - 1)});
    plan.panels.push_back({cuts[i], "cut f" + std::to_string(cuts[i])});
    plan.cut_after.push_back(true);
    plan.cut_after.push_back(false);
  }
  const std::string shown = std::to_string(std::min<size_t>(cuts.size(), 2));
  plan.caption = cuts.empty() ? "middle frame (no boundary recorded)"
                              : "frames either side of " + shown + " of " +
                                    std::to_string(cuts.size()) + " cut(s)";
}

// Two frames half a second apart around the middle, for motion vectors.
void PlanMotion(const VideoGeometry& g, const ClipSpan& span, PanelPlan& plan) {
  const std::int64_t step = std::max<std::int64_t>(1, std::llround(g.fps > 0 ? g.fps / 2 : 15));
  const std::int64_t a = std::max(span.first, span.mid - step);
  const std::int64_t b = std::min(std::max(a + 1, span.mid), span.last);
  plan.panels.push_back({a, "f" + std::to_string(a)});
  plan.panels.push_back({b, "f" + std::to_string(b) + " motion"});
  plan.cut_after = {false, false};
  plan.caption = "camera motion from frame " + std::to_string(a) + " to " + std::to_string(b) +
                 " (Lucas-Kanade tracks)";
}

// The first frame where a box (hands first) touches the border.
void PlanBorder(const ThumbnailRequest& request, const VideoGeometry& g, const ClipSpan& span,
                PanelPlan& plan) {
  std::vector<Detection> sorted = request.detections;
  std::stable_sort(sorted.begin(), sorted.end(), [](const Detection& x, const Detection& y) {
    return std::make_pair(x.frame, x.kind != "hand") < std::make_pair(y.frame, y.kind != "hand");
  });
  bool found = false;
  for (const auto& det : sorted) {
    if (det.frame < span.first || det.frame > span.last) continue;
    if (TouchesBorder(det, g.full_width, g.full_height)) {
      plan.border_box = det;
      found = true;
      break;
    }
  }
  const std::int64_t f = found ? plan.border_box.frame : span.mid;
  plan.panels.push_back({f, "f" + std::to_string(f)});
  plan.cut_after = {false};
  if (found) plan.highlight_panel = 0;
  plan.caption = found ? "first frame where a " + plan.border_box.kind + " box touches the border"
                       : "middle frame; no box touches the border (hand or object missing)";
}

PanelPlan PlanPanels(const ThumbnailRequest& request, const std::string& kind,
                     const VideoGeometry& g, const ClipSpan& span) {
  PanelPlan plan;
  if (kind == "cut") {
    PlanCuts(request, span, plan);
  } else if (kind == "motion") {
    PlanMotion(g, span, plan);
  } else if (kind == "border") {
    PlanBorder(request, g, span, plan);
  } else if (kind == "activity") {
    plan.panels.push_back({span.first, "first f" + std::to_string(span.first)});
    plan.panels.push_back({span.mid, "f" + std::to_string(span.mid)});
    plan.panels.push_back({span.last, "last f" + std::to_string(span.last)});
    plan.cut_after = {false, false, false};
    plan.caption = "first, middle and last frame of the clip";
  }
  if (plan.panels.empty()) {
    plan.panels.push_back({span.mid, "f" + std::to_string(span.mid)});
    plan.cut_after = {false};
    if (plan.caption.empty()) plan.caption = "middle frame with hand and object boxes";
  }
  return plan;
}

// One sequential pass collects every frame the panels need; a panel past
// the decodable end shows the last decoded frame (a file that ends early
// still shows what could be decoded, and the caption says so).
void DecodePanels(VideoDecoder& decoder, PanelPlan& plan) {
  std::set<std::int64_t> wanted;
  for (const auto& p : plan.panels) wanted.insert(p.frame);
  std::map<std::int64_t, cv::Mat> frames;
  AnalysisFrame frame;
  std::int64_t last_index = -1;
  cv::Mat last_decoded;
  try {
    while (frames.size() < wanted.size() && decoder.Next(&frame)) {
      if (wanted.count(frame.index)) frames[frame.index] = frame.bgr.clone();
      if (frame.index >= *wanted.rbegin()) break;
      frame.bgr.copyTo(last_decoded);
      last_index = frame.index;
    }
  } catch (const Error& e) {
    if (frames.empty() && last_decoded.empty()) throw;
    plan.caption += " (video ends early: " + e.message() + ")";
  }
  for (auto& p : plan.panels) {
    auto it = frames.find(p.frame);
    if (it == frames.end()) {
      if (last_decoded.empty()) throw Error("video_read_failed", "no frame could be decoded");
      it = frames.emplace(last_index, last_decoded).first;
      p.frame = last_index;
    }
    p.image = it->second.clone();
  }
}

// Marks the border box on `p` (and the border edges it touches); returns its
// index among `boxes`, or -1.
int HighlightBorder(Panel& p, const std::vector<Detection>& boxes, const Detection& box,
                    const VideoGeometry& g) {
  int highlight = -1;
  for (size_t k = 0; k < boxes.size(); ++k) {
    if (boxes[k].kind == box.kind && boxes[k].x1 == box.x1 && boxes[k].y1 == box.y1 &&
        boxes[k].x2 == box.x2 && boxes[k].y2 == box.y2) {
      highlight = static_cast<int>(k);
    }
  }
  const int w = p.image.cols - 1, h = p.image.rows - 1;
  const double m = 2.0;
  if (box.x1 <= m) cv::line(p.image, {0, 0}, {0, h}, kHighlight, 3);
  if (box.y1 <= m) cv::line(p.image, {0, 0}, {w, 0}, kHighlight, 3);
  if (box.x2 >= g.full_width - m) cv::line(p.image, {w, 0}, {w, h}, kHighlight, 3);
  if (box.y2 >= g.full_height - m) cv::line(p.image, {0, h}, {w, h}, kHighlight, 3);
  return highlight;
}

// Boxes on every panel, the border highlight, and motion vectors on the
// second panel of a motion strip.
void DrawPanels(const ThumbnailRequest& request, const ThumbnailOptions& options,
                const std::string& kind, const VideoGeometry& g, PanelPlan& plan) {
  const double scale = 1.0 / g.downscale;
  std::vector<MotionVector> vectors;
  if (kind == "motion" && plan.panels.size() == 2) {
    vectors = TrackMotion(plan.panels[0].image, plan.panels[1].image);
  }
  for (size_t i = 0; i < plan.panels.size(); ++i) {
    Panel& p = plan.panels[i];
    std::int64_t from = -1;
    auto boxes = BoxesNear(request.detections, p.frame, options.box_search_frames, &from);
    const int highlight = static_cast<int>(i) == plan.highlight_panel
                              ? HighlightBorder(p, boxes, plan.border_box, g)
                              : -1;
    DrawDetections(p.image, boxes, scale, highlight);
    if (kind == "motion" && i == 1) {
      for (const auto& v : vectors) {
        cv::arrowedLine(p.image, v.from, v.to, kArrowColour, 1, cv::LINE_AA, 0, 0.3);
        cv::circle(p.image, v.from, 1, kArrowColour, cv::FILLED);
      }
    }
  }
  if (kind == "motion") plan.caption += ", " + std::to_string(vectors.size()) + " tracks";
}

// Decodes, draws and encodes the strip into `t`. Throws Error or
// cv::Exception for an unreadable video.
void RenderStrip(const ThumbnailRequest& request, const ThumbnailOptions& options,
                 Thumbnail& t) {
  DecoderOptions d;
  d.analysis_size = options.analysis_size;
  d.clip = t.label;
  const ClipRecord& c = request.clip;
  if (c.start_frame) d.first_frame = *c.start_frame;
  else if (c.start_s) d.first_s = *c.start_s;
  VideoDecoder decoder(request.video_path, d);
  const VideoGeometry& g = decoder.geometry();
  const std::string kind = OverlayKind(request.stage, request.reason);
  PanelPlan plan = PlanPanels(request, kind, g, SpanOf(c, decoder));
  t.caption = plan.caption;  // kept when decoding fails
  DecodePanels(decoder, plan);
  DrawPanels(request, options, kind, g, plan);
  t.caption = plan.caption;
  const cv::Mat strip = Compose(plan.panels, options.panel_height, plan.cut_after);
  std::vector<unsigned char> jpeg;
  cv::imencode(".jpg", strip, jpeg, {cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality});
  t.jpeg_base64 = Base64(jpeg);
  t.width = strip.cols;
  t.height = strip.rows;
}

}  // namespace

Thumbnail MakeThumbnail(const ThumbnailRequest& request, const ThumbnailOptions& options) {
  Thumbnail t;
  t.clip = request.clip.id;
  t.label = ClipLabel(request.clip);
  const std::string& path = request.video_path;
  if (path.find("://") != std::string::npos) {
    t.note = "clip " + t.label + ": video " + path + " is a URL; the report reads local files only";
    return t;
  }
  if (!std::filesystem::exists(path)) {
    t.note = "clip " + t.label + ": video file not found: " + path;
    return t;
  }
  try {
    RenderStrip(request, options, t);
  } catch (const Error& e) {
    t.note = "clip " + t.label + ": cannot read video " + path + ": " + e.what();
  } catch (const cv::Exception& e) {
    t.note = "clip " + t.label + ": cannot read video " + path + ": " + e.what();
  }
  return t;
}

}  // namespace doasido::reports
