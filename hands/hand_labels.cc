#include "hands/hand_labels.h"

#include <algorithm>
#include <limits>

#include "core/config.h"
#include "core/error.h"
#include "core/file_text.h"
#include "core/geometry.h"

namespace doasido::hands {
namespace {

[[noreturn]] void Bad(const std::filesystem::path& file, const std::string& field,
                      const std::string& why) {
  throw Error("bad_labels", why, {.file = file.string(), .field = field});
}

double BoxSize(const LabelledHand& h) {
  const auto [lo, hi] = VisibleBounds(h);
  return std::max(1.0, (hi - lo).maxCoeff());
}

}  // namespace

std::pair<Eigen::Vector2d, Eigen::Vector2d> VisibleBounds(const LabelledHand& h) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (int j = 0; j < kJoints; ++j) {
    if (!h.visible[j]) continue;
    lo = lo.cwiseMin(h.uv[j]);
    hi = hi.cwiseMax(h.uv[j]);
  }
  return {lo, hi};
}

HandLabels ReadHandLabels(const std::filesystem::path& file) {
  Json j;
  try {
    j = Json::parse(ReadFileOrThrow(file, "bad_labels", "cannot read the label file"));
  } catch (const Json::exception& e) {
    Bad(file, "", std::string("not JSON: ") + e.what());
  }
  HandLabels out;
  try {
    out.video = j.at("video").get<std::string>();
    out.labeller = j.value("labeller", "");
    for (const Json& f : j.at("frames")) {
      LabelledFrame frame;
      frame.frame = f.at("frame").get<int>();
      for (const Json& h : f.at("hands")) {
        LabelledHand hand;
        const std::string side = h.at("side").get<std::string>();
        if (side != "right" && side != "left")
          Bad(file, "side", "side must be right or left: " + side);
        hand.side = side == "right" ? Side::kRight : Side::kLeft;
        const Json& kp = h.at("keypoints_2d");
        if (kp.size() != kJoints) Bad(file, "keypoints_2d", "21 keypoints expected");
        for (int k = 0; k < kJoints; ++k) {
          hand.uv[k] = {kp[k].at(0).get<double>(), kp[k].at(1).get<double>()};
          hand.visible[k] = h.contains("visible") ? h["visible"].at(k).get<bool>() : true;
        }
        frame.hands.push_back(hand);
      }
      out.frames.push_back(std::move(frame));
    }
  } catch (const Json::exception& e) {
    Bad(file, "frames", e.what());
  }
  return out;
}

void PckScore::Add(const PckScore& o) {
  keypoints += o.keypoints;
  within_01 += o.within_01;
  within_02 += o.within_02;
  hands += o.hands;
  missed += o.missed;
  swaps += o.swaps;
  error_px += o.error_px;
  error_boxes += o.error_boxes;
  found_keypoints += o.found_keypoints;
}

PckScore ScoreFrame(const LabelledFrame& labels, const std::vector<PredictedHand>& predicted) {
  PckScore s;
  std::vector<bool> used(predicted.size(), false);
  for (const LabelledHand& l : labels.hands) {
    ++s.hands;
    const double box = BoxSize(l);
    int visible = 0;
    for (int j = 0; j < kJoints; ++j) visible += l.visible[j] ? 1 : 0;
    s.keypoints += visible;
    if (!visible) continue;
    double best = std::numeric_limits<double>::infinity();
    int best_k = -1;
    for (size_t k = 0; k < predicted.size(); ++k) {
      if (used[k]) continue;
      double sum = 0;
      for (int j = 0; j < kJoints; ++j) {
        if (l.visible[j]) sum += (predicted[k].uv[j] - l.uv[j]).norm();
      }
      if (sum / visible < best) {
        best = sum / visible;
        best_k = static_cast<int>(k);
      }
    }
    if (best_k < 0 || best > box) {
      ++s.missed;
      continue;
    }
    used[best_k] = true;
    if (predicted[best_k].side != l.side) ++s.swaps;
    for (int j = 0; j < kJoints; ++j) {
      if (!l.visible[j]) continue;
      const double d = (predicted[best_k].uv[j] - l.uv[j]).norm();
      s.within_01 += d <= 0.1 * box ? 1 : 0;
      s.within_02 += d <= 0.2 * box ? 1 : 0;
      s.error_px += d;
      s.error_boxes += d / box;
      ++s.found_keypoints;
    }
  }
  return s;
}

LabelScores ScoreLabels(const HandLabels& labels, const DetectedFrames& detected,
                        const HandsResult& result) {
  const Camera cam = Camera::FromK(result.intrinsics.K, 0, 0);
  LabelScores s;
  for (const LabelledFrame& l : labels.frames) {
    const int f = l.frame - static_cast<int>(detected.first_frame);
    if (f < 0 || f >= static_cast<int>(detected.frames.size())) continue;
    ++s.labelled_frames;
    std::vector<PredictedHand> raw, tracked, fitted;
    for (const HandObservation& o : detected.frames[f]) {
      raw.push_back({.side = o.p_right >= 0.5 ? Side::kRight : Side::kLeft, .uv = o.uv});
    }
    for (const FittedTrack& t : result.tracks) {
      const int k = f - t.first_frame;
      if (k < 0 || k >= static_cast<int>(t.joints.size())) continue;
      if (t.observations[k]) tracked.push_back({.side = t.side, .uv = t.observations[k]->uv});
      PredictedHand p{.side = t.side};
      for (int j = 0; j < kJoints; ++j) p.uv[j] = cam.Project(t.joints[k][j]);
      fitted.push_back(p);
    }
    s.models.Add(ScoreFrame(l, raw));
    s.tracker.Add(ScoreFrame(l, tracked));
    s.fit.Add(ScoreFrame(l, fitted));
  }
  return s;
}

}  // namespace doasido::hands
