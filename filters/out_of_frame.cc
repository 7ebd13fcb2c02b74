#include "filters/out_of_frame.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "core/error.h"
#include "filters/verdict.h"

namespace doasido::filters {

Json ToJson(const OutOfFrameSignals& s) {
  Json j{{"covered", s.covered},
              {"hands", s.hands},
              {"hand_cut", s.hand_cut},
              {"object_needed", s.object_needed},
              {"object_missing", s.object_missing},
              {"object_cut", s.object_cut}};
  if (!s.hands_complete) j["hands_complete"] = false;
  return j;
}

OutOfFrameSignals OutOfFrameSignalsFromJson(const Json& j) {
  OutOfFrameSignals s;
  s.covered = IntArray(j, "covered");
  s.hands = IntArray(j, "hands");
  s.hand_cut = IntArray(j, "hand_cut");
  s.object_needed = IntArray(j, "object_needed");
  s.object_missing = IntArray(j, "object_missing");
  s.object_cut = IntArray(j, "object_cut");
  s.hands_complete = j.value("hands_complete", true);
  const size_t n = s.covered.size();
  if (s.hands.size() != n || s.hand_cut.size() != n || s.object_needed.size() != n ||
      s.object_missing.size() != n || s.object_cut.size() != n) {
    throw Error("bad_measurements", "per-frame arrays differ in length", {.field = "out_of_frame"});
  }
  return s;
}

int TouchedObject(const cv::Rect2d& hand, const std::vector<cv::Rect2d>& objects) {
  const cv::Rect2d grown(hand.x - hand.width / 2, hand.y - hand.height / 2, hand.width * 2,
                         hand.height * 2);
  const cv::Point2d hc(hand.x + hand.width / 2, hand.y + hand.height / 2);
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < objects.size(); ++i) {
    if ((grown & objects[i]).area() <= 0) continue;
    const cv::Point2d oc(objects[i].x + objects[i].width / 2, objects[i].y + objects[i].height / 2);
    const double d = std::hypot(oc.x - hc.x, oc.y - hc.y);
    if (d < best_d) {
      best_d = d;
      best = static_cast<int>(i);
    }
  }
  return best;
}

bool OutOfFrameExtractor::AtBorder(const cv::Rect2d& b) const {
  const double mx = config_.border_margin * geometry_.width;
  const double my = config_.border_margin * geometry_.height;
  return b.x <= mx || b.y <= my || b.x + b.width >= geometry_.width - mx ||
         b.y + b.height >= geometry_.height - my;
}

void OutOfFrameExtractor::Consume(FrameContext& context) {
  const FrameBoxes& boxes = context.boxes;
  int hand_cut = 0, needed = 0, missing = 0, object_cut = 0;
  if (boxes.known) {
    for (size_t h = 0; h < boxes.hands.size(); ++h) {
      if (AtBorder(boxes.hands[h])) hand_cut = 1;
      const int state = h < boxes.hand_contact.size() ? boxes.hand_contact[h] : -1;
      const int touched = TouchedObject(boxes.hands[h], boxes.objects);
      const bool contact = state == 3 || state == 4 || (state < 0 && touched >= 0);
      if (!contact) continue;
      needed = 1;
      if (touched < 0) {
        if (boxes.objects.empty()) missing = 1;
        continue;
      }
      if (AtBorder(boxes.objects[touched])) object_cut = 1;
    }
  }
  signals_.covered.push_back(boxes.known ? 1 : 0);
  if (boxes.known && !boxes.complete) signals_.hands_complete = false;
  signals_.hands.push_back(static_cast<int>(boxes.hands.size()));
  signals_.hand_cut.push_back(hand_cut);
  signals_.object_needed.push_back(needed);
  signals_.object_missing.push_back(missing);
  signals_.object_cut.push_back(object_cut);
}

OutOfFrameSummary SummarizeOutOfFrame(const OutOfFrameSignals& s, std::int64_t first,
                                      std::int64_t last) {
  OutOfFrameSummary out;
  first = std::max<std::int64_t>(0, first);
  last = std::min<std::int64_t>(last, static_cast<std::int64_t>(s.covered.size()) - 1);
  std::map<int, int> frames_with;  // hand count -> covered frames
  int covered = 0;
  for (std::int64_t i = first; i <= last; ++i) {
    if (!s.covered[i]) continue;
    ++covered;
    ++frames_with[s.hands[i]];
  }
  if (last >= first) {
    out.covered_fraction = static_cast<double>(covered) / static_cast<double>(last - first + 1);
  }
  if (covered == 0) return out;
  for (const auto& [hands, n] : frames_with) {
    if (n >= 0.2 * covered) out.expected_hands = std::max(out.expected_hands, hands);
  }
  int missing = 0, cut = 0, outs = 0, hand_missing = 0, hand_cut = 0, object_missing = 0,
      object_cut = 0;
  for (std::int64_t i = first; i <= last; ++i) {
    if (!s.covered[i]) continue;
    const bool hm = s.hands_complete && s.hands[i] < out.expected_hands;
    const bool m = hm || s.object_missing[i];
    const bool c = s.hand_cut[i] || s.object_cut[i];
    missing += m;
    cut += c;
    outs += m || c;
    hand_missing += hm;
    hand_cut += s.hand_cut[i] != 0;
    object_missing += s.object_missing[i] != 0;
    object_cut += s.object_cut[i] != 0;
  }
  const double n = covered;
  out.missing_fraction = missing / n;
  out.cut_fraction = cut / n;
  out.out_fraction = outs / n;
  out.hand_missing_fraction = hand_missing / n;
  out.hand_cut_fraction = hand_cut / n;
  out.object_missing_fraction = object_missing / n;
  out.object_cut_fraction = object_cut / n;
  return out;
}

FilterVerdict DecideOutOfFrame(const Json& measurements, const OutOfFrameConfig& c) {
  RequireAnalysis(measurements, kOutOfFrameStageName);
  const OutOfFrameSignals s = OutOfFrameSignalsFromJson(measurements.at("signals"));
  const ShotSpan span = SpanOf(measurements, static_cast<std::int64_t>(s.covered.size()));
  const OutOfFrameSummary m = SummarizeOutOfFrame(s, span.first, span.last);
  FilterVerdict result;
  result.measurements = measurements;
  result.measurements["summary"] = {{"covered_fraction", m.covered_fraction},
                                    {"expected_hands", m.expected_hands},
                                    {"missing_fraction", m.missing_fraction},
                                    {"cut_fraction", m.cut_fraction},
                                    {"out_fraction", m.out_fraction},
                                    {"hand_missing_fraction", m.hand_missing_fraction},
                                    {"hand_cut_fraction", m.hand_cut_fraction},
                                    {"object_missing_fraction", m.object_missing_fraction},
                                    {"object_cut_fraction", m.object_cut_fraction},
                                    {"scores",
                                     {ScoreEntry("missing_fraction", m.missing_fraction, true,
                                                 c.reject_missing_fraction,
                                                 c.flag_missing_fraction),
                                      ScoreEntry("cut_fraction", m.cut_fraction, true,
                                                 c.reject_cut_fraction, c.flag_cut_fraction)}}};
  if (m.covered_fraction < c.min_covered_fraction) {
    SetVerdict(result, Verdict::kFlag, kReasonNoDetections);
  } else if (m.missing_fraction >= c.reject_missing_fraction ||
             m.cut_fraction >= c.reject_cut_fraction) {
    SetVerdict(result, Verdict::kReject, kReasonOutOfFrame);
  } else if (m.missing_fraction >= c.flag_missing_fraction ||
             m.cut_fraction >= c.flag_cut_fraction) {
    SetVerdict(result, Verdict::kFlag, kReasonOutOfFrame);
  }
  return result;
}

}  // namespace doasido::filters
