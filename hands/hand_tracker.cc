#include "hands/hand_tracker.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/hand_keypoints.h"

namespace doasido::hands {
namespace {

Eigen::Vector2d Centre(const HandObservation& o) {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& p : o.uv) c += p;
  return c / kJoints;
}

// The hand's size in the image: the diagonal of its keypoints' box.
double Size(const HandObservation& o) {
  Eigen::Vector2d lo = o.uv[0], hi = o.uv[0];
  for (const auto& p : o.uv) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return std::max(1.0, (hi - lo).norm());
}

const HandObservation& LastSeen(const Track& t) { return *t.frames.back(); }

// Two detections of one frame are the same hand found twice (the
// landmarker sometimes keeps a second crop on one hand) when their
// keypoints lie on average within `duplicate_distance` hand sizes (the
// smaller's) of each other.
bool SameHand(const HandObservation& a, const HandObservation& b, double duplicate_distance) {
  double sum = 0;
  for (int j = 0; j < kJoints; ++j) sum += (a.uv[j] - b.uv[j]).norm();
  return sum / kJoints < duplicate_distance * std::min(Size(a), Size(b));
}

// Links detections to the open tracks of frame `f`, nearest pair first. A
// detection left over that is the same hand as one taken (or, among new
// hands, as a surer one) is dropped: the one nearest the track continues
// it, so a hand found twice does not alternate between the two finds.
void LinkFrame(const FrameObservations& hands, int f, const TrackerConfig& config,
               std::vector<Track>& open, std::vector<Track>& closed, int& duplicates) {
  // Close tracks unseen for too long.
  for (auto it = open.begin(); it != open.end();) {
    if (f - it->last_frame() > config.max_gap_frames + 1) {
      closed.push_back(std::move(*it));
      it = open.erase(it);
    } else {
      ++it;
    }
  }
  struct Pair {
    double cost;
    size_t track, hand;
  };
  std::vector<Pair> pairs;
  for (size_t t = 0; t < open.size(); ++t) {
    const HandObservation& last = LastSeen(open[t]);
    for (size_t h = 0; h < hands.size(); ++h) {
      const double jump = (Centre(hands[h]) - Centre(last)).norm() / Size(last);
      if (jump < config.max_jump) pairs.push_back({jump, t, h});
    }
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const Pair& a, const Pair& b) { return a.cost < b.cost; });
  std::vector<bool> track_used(open.size(), false), hand_used(hands.size(), false);
  for (const Pair& p : pairs) {
    if (track_used[p.track] || hand_used[p.hand]) continue;
    track_used[p.track] = hand_used[p.hand] = true;
    Track& t = open[p.track];
    t.frames.resize(static_cast<size_t>(f - t.first_frame), std::nullopt);
    t.frames.push_back(hands[p.hand]);
  }
  std::vector<size_t> order(hands.size());
  for (size_t h = 0; h < hands.size(); ++h) order[h] = h;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return hands[a].score > hands[b].score; });
  std::vector<size_t> taken;
  for (size_t h = 0; h < hands.size(); ++h) {
    if (hand_used[h]) taken.push_back(h);
  }
  for (size_t h : order) {
    if (hand_used[h]) continue;
    if (config.duplicate_distance > 0 && std::any_of(taken.begin(), taken.end(), [&](size_t k) {
          return SameHand(hands[h], hands[k], config.duplicate_distance);
        })) {
      ++duplicates;
      continue;
    }
    taken.push_back(h);
    Track t;
    t.first_frame = f;
    t.frames.push_back(hands[h]);
    open.push_back(std::move(t));
  }
}

// A shadow: a track that, on at least half of its observed frames, lies
// within twice `duplicate_distance` of a track seen longer (the same hand
// found twice for a few frames, where single frames straddle the
// threshold: 02_cups 264-271, 0.43-0.53 hand sizes apart). Shadows are
// dropped; their detections count as duplicates.
std::vector<Track> WithoutShadows(std::vector<Track> tracks, double duplicate_distance,
                                  int& duplicates) {
  if (duplicate_distance <= 0) return tracks;
  std::vector<bool> shadow(tracks.size(), false);
  for (size_t a = 0; a < tracks.size(); ++a) {
    const Track& t = tracks[a];
    int near = 0;
    for (int f = t.first_frame; f <= t.last_frame(); ++f) {
      const auto& o = t.frames[static_cast<size_t>(f - t.first_frame)];
      if (!o) continue;
      for (size_t b = 0; b < tracks.size(); ++b) {
        const Track& u = tracks[b];
        if (b == a || u.observed() <= t.observed() || f < u.first_frame || f > u.last_frame())
          continue;
        const auto& p = u.frames[static_cast<size_t>(f - u.first_frame)];
        if (p && SameHand(*o, *p, 2 * duplicate_distance)) {
          ++near;
          break;
        }
      }
    }
    shadow[a] = 2 * near >= t.observed();
  }
  std::vector<Track> kept;
  for (size_t a = 0; a < tracks.size(); ++a) {
    if (shadow[a]) {
      duplicates += tracks[a].observed();
    } else {
      kept.push_back(std::move(tracks[a]));
    }
  }
  return kept;
}

double Vote(const Track& t) {
  double sum = 0, weight = 0;
  for (const auto& o : t.frames) {
    if (!o) continue;
    sum += o->score * o->p_right;
    weight += o->score;
  }
  return weight > 0 ? sum / weight : 0.5;
}

bool Overlap(const Track& a, const Track& b) {
  return a.first_frame <= b.last_frame() && b.first_frame <= a.last_frame();
}

// Where the model's handedness cannot be right (two hands seen together
// voting alike), the side one person's two hands must have by where they
// are: the arms come from the body, so where the fingers point down the
// image (wrist above the middle finger's base) the person faces the camera
// across the hands (02_cups, 03_blocks) and their right hand is at the
// image's left; where the fingers point up (one's own view, over the
// shoulder) the right hand is at the image's right. Every labelled
// two-hand frame of bench/hand_labels agrees. The side of `t` against
// `k` over the frames both observe, or nullopt where the fingers point
// across (under `min_lean` of the hand's size) or the two never share a
// frame.
std::optional<Side> ArrangedSide(const Track& t, const Track& k, double min_lean) {
  double lean = 0, left_of = 0;
  int shared = 0;
  for (int f = std::max(t.first_frame, k.first_frame); f <= std::min(t.last_frame(), k.last_frame());
       ++f) {
    const auto& a = t.frames[static_cast<size_t>(f - t.first_frame)];
    const auto& b = k.frames[static_cast<size_t>(f - k.first_frame)];
    if (!a || !b) continue;
    for (const HandObservation* o : {&*a, &*b}) {
      lean += (o->uv[kMiddleBase].y() - o->uv[kWrist].y()) / Size(*o) / 2;
    }
    left_of += Centre(*a).x() < Centre(*b).x() ? 1 : -1;
    ++shared;
  }
  if (shared == 0 || std::abs(lean / shared) < min_lean || left_of == 0) return std::nullopt;
  const bool fingers_down = lean > 0;
  const bool t_left_in_image = left_of > 0;
  return fingers_down == t_left_in_image ? Side::kRight : Side::kLeft;
}

// Sides: surest votes first; a side already held by an overlapping track
// goes to the other side, unless the two hands' arrangement in the image
// (ArrangedSide) gives it to this one, when the held track takes the
// other; a track with both sides taken is dropped.
std::vector<Track> AssignSides(std::vector<Track> tracks, double min_lean, TrackingSummary& summary) {
  for (Track& t : tracks) t.side_vote = Vote(t);
  std::sort(tracks.begin(), tracks.end(), [](const Track& a, const Track& b) {
    const double sa = std::abs(a.side_vote - 0.5) * a.observed();
    const double sb = std::abs(b.side_vote - 0.5) * b.observed();
    return sa > sb;
  });
  std::vector<Track> kept;
  const auto holders = [&](Side s, const Track& t) {
    std::vector<Track*> out;
    for (Track& k : kept) {
      if (k.side == s && Overlap(k, t)) out.push_back(&k);
    }
    return out;
  };
  for (Track& t : tracks) {
    const Side wanted = t.side_vote >= 0.5 ? Side::kRight : Side::kLeft;
    const Side other = wanted == Side::kRight ? Side::kLeft : Side::kRight;
    const std::vector<Track*> held = holders(wanted, t);
    if (held.size() == 1 && min_lean > 0 && ArrangedSide(t, *held[0], min_lean) == wanted) {
      Track& k = *held[0];
      const bool k_free = std::none_of(kept.begin(), kept.end(), [&](const Track& j) {
        return &j != &k && j.side == other && Overlap(j, k);
      });
      if (k_free) {
        k.side = other;
        ++summary.side_changes;
        t.side = wanted;
        kept.push_back(std::move(t));
        continue;
      }
    }
    if (held.empty()) {
      t.side = wanted;
    } else if (holders(other, t).empty()) {
      t.side = other;
      ++summary.side_changes;
    } else {
      ++summary.dropped_tracks;
      continue;
    }
    kept.push_back(std::move(t));
  }
  std::sort(kept.begin(), kept.end(),
            [](const Track& a, const Track& b) { return a.first_frame < b.first_frame; });
  return kept;
}

}  // namespace

int Track::observed() const {
  return static_cast<int>(
      std::count_if(frames.begin(), frames.end(), [](const auto& o) { return o.has_value(); }));
}

std::vector<Track> BuildTracks(const std::vector<FrameObservations>& frames,
                               const TrackerConfig& config, TrackingSummary* summary) {
  TrackingSummary local;
  TrackingSummary& s = summary ? *summary : local;
  s = {};
  std::vector<Track> open, closed;
  for (size_t f = 0; f < frames.size(); ++f) {
    FrameObservations hands;
    for (const HandObservation& o : frames[f]) {
      if (o.score >= config.min_score) hands.push_back(o);
    }
    s.detections += static_cast<int>(hands.size());
    LinkFrame(hands, static_cast<int>(f), config, open, closed, s.duplicates);
  }
  for (Track& t : open) closed.push_back(std::move(t));
  closed = WithoutShadows(std::move(closed), config.duplicate_distance, s.duplicates);
  std::vector<Track> long_enough;
  for (Track& t : closed) {
    if (t.observed() >= config.min_track_frames) {
      long_enough.push_back(std::move(t));
    } else {
      ++s.dropped_tracks;
    }
  }
  return AssignSides(std::move(long_enough), config.min_arrangement_lean, s);
}

}  // namespace doasido::hands
