#include "objects/object_reconstruction.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/error.h"
#include "core/hand_keypoints.h"
#include "objects/held_object.h"
#include "objects/object_categories.h"
#include "objects/object_scale.h"
#include "objects/object_track_fit.h"

namespace doasido::objects {
namespace {


double Cross(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

// The convex hull of the eight corners, counter-clockwise (monotone chain).
std::vector<Vec2> CornerHull(const BoxKeypoints& k) {
  std::vector<Vec2> p(k.begin() + 1, k.end());
  std::sort(p.begin(), p.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  std::vector<Vec2> hull(2 * p.size());
  size_t n = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (n >= 2 && Cross(hull[n - 2], hull[n - 1], p[i]) <= 0) --n;
    hull[n++] = p[i];
  }
  const size_t lower = n + 1;
  for (int i = static_cast<int>(p.size()) - 2; i >= 0; --i) {
    while (n >= lower && Cross(hull[n - 2], hull[n - 1], p[i]) <= 0) --n;
    hull[n++] = p[i];
  }
  hull.resize(n > 1 ? n - 1 : n);
  return hull;
}

bool InsideHull(const std::vector<Vec2>& hull, const Vec2& q) {
  if (hull.size() < 3) return false;
  for (size_t i = 0; i < hull.size(); ++i) {
    if (Cross(hull[i], hull[(i + 1) % hull.size()], q) < 0) return false;
  }
  return true;
}

double MedianOf(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// The track's box proportions, geometric mean 1: per axis the median of
// its frames' lifted extents (the thin-slab frames only when every frame is
// one). A round object's thin slab, seen from the side, shows its diameter
// as its wider width: both widths are taken as that one.
Vec3 TrackShape(const std::vector<LiftedBox>& lifts, bool symmetric) {
  bool any_sound = false;
  for (const LiftedBox& l : lifts) any_sound |= !l.degenerate;
  std::array<std::vector<double>, 3> logs;
  for (const LiftedBox& l : lifts) {
    if (any_sound && l.degenerate) continue;
    Vec3 s = l.size;
    if (symmetric && l.degenerate) s.x() = s.z() = std::max(s.x(), s.z());
    for (int k = 0; k < 3; ++k) logs[k].push_back(std::log(s[k]));
  }
  Vec3 shape;
  for (int k = 0; k < 3; ++k) shape[k] = std::exp(MedianOf(logs[k]));
  return shape / CharacteristicSize(shape);
}

// The object's own proportions in the box's units: a round object's
// diameter is the mean of the box's two widths (a handle widens one).
Vec3 ObjectShape(const Vec3& box, bool symmetric) {
  if (!symmetric) return box;
  const double diameter = (box.x() + box.z()) / 2;
  return {diameter, box.y(), diameter};
}

// Poses interpolated across a gap: the centre linearly, the rotation by slerp.
Pose Interpolate(const Pose& a, const Pose& b, double s) {
  return {a.q.slerp(s, b.q), (1 - s) * a.t + s * b.t};
}

// The keypoints in K's pixels: the record's origin is the top-left pixel's
// corner (objects/box_keypoints.h), K's pixel centres are integers.
BoxKeypoints InKPixels(const ObjectObservation& o) {
  BoxKeypoints k = o.keypoints_2d;
  for (Vec2& p : k) p -= Vec2(0.5, 0.5);
  return k;
}

struct Lifted {
  int frame;
  BoxKeypoints keypoints;  // K's pixels
  LiftedBox lift;
  UnitPose unit;
};

// Fingertips of either hand that project inside the frame's box.
void CollectContacts(const recon::ClipBundle& hands, const Mat3& K, const Lifted& l, int index,
                     std::vector<FingertipContact>& contacts, int& frames_with_contact) {
  const std::vector<Vec2> hull = CornerHull(l.keypoints);
  bool any = false;
  for (const auto* side : {&hands.hand_left, &hands.hand_right}) {
    if (!side->has_value()) continue;
    const recon::HandTrack& h = **side;
    const size_t t = static_cast<size_t>(l.frame);
    if (t >= h.valid.size() || !h.valid[t]) continue;
    for (int tip : kFingertips) {
      const Vec3 f = h.joints[t].row(tip).transpose();
      if (!f.allFinite() || f.z() <= 0) continue;
      const Vec3 uv = K * f;
      if (!InsideHull(hull, uv.head<2>() / uv.z())) continue;
      contacts.push_back({index, f});
      any = true;
    }
  }
  frames_with_contact += any;
}

// One track from its observations (sorted by frame, one per frame).
ObjectTrack LiftTrack(const std::vector<const ObjectObservation*>& obs, const CategoryPrior& prior,
                      const recon::ClipBundle& hands, const ObjectsConfig& config) {
  const Mat3& K = hands.KAt(0);
  ObjectTrack out;
  out.track = obs.front()->track;
  out.category = prior.category;
  out.symmetric = prior.rotationally_symmetric;
  out.frames.assign(hands.frames, ObjectFrame{});
  std::vector<Lifted> lifted;
  for (const ObjectObservation* o : obs) {
    ObjectFrame& f = out.frames[o->frame];
    f.observed = true;
    f.score = o->score;
    f.keypoints = o->keypoints_2d;
    try {
      const BoxKeypoints k = InKPixels(*o);
      lifted.push_back({o->frame, k, LiftBox(k, K, config.degenerate_ratio), {}});
    } catch (const Error&) {
      // No box in front of the camera: the frame is filled like a gap.
    }
  }
  if (lifted.empty()) return out;
  std::vector<LiftedBox> lifts;
  for (const Lifted& l : lifted) lifts.push_back(l.lift);
  // The box the keypoints show is fitted; the object (a cylinder for round
  // ones) is what the size and the mesh describe.
  const Vec3 shape = TrackShape(lifts, out.symmetric);
  const Vec3 object_shape = ObjectShape(shape, out.symmetric);
  for (Lifted& l : lifted) {
    out.frames[l.frame].degenerate = l.lift.degenerate;
    const bool side_view = out.symmetric && l.lift.degenerate;
    const Pose start = side_view ? SideViewPose(l.keypoints, K, shape.y())
                                 : Pose{Quat(l.lift.R), l.lift.t};
    const Pose p = PoseForShape(l.keypoints, K, shape, start, side_view);
    l.unit = {p.R(), p.t};
  }
  // The scale.
  std::vector<UnitPose> units;
  std::vector<FingertipContact> contacts;
  for (size_t i = 0; i < lifted.size(); ++i) {
    units.push_back(lifted[i].unit);
    CollectContacts(hands, K, lifted[i], static_cast<int>(i), contacts, out.contact_frames);
  }
  const double prior_scale = CharacteristicSize(prior.size_m) / CharacteristicSize(object_shape);
  double scale = prior_scale;
  out.scale_source = kScaleFromPrior;
  if (out.contact_frames >= config.min_contact_frames) {
    const ContactScale fit = FitContactScale(
        units, object_shape, out.symmetric, contacts, prior_scale,
        {.fingertip_offset_m = config.fingertip_offset_m, .robust_m = config.contact_robust_m});
    out.contact_residual_m = fit.residual_median_m;
    if (fit.residual_median_m <= config.max_contact_residual_m) {
      scale = fit.scale;
      out.scale_source = kScaleFromHand;
    }
  }
  out.scale_assumed = out.scale_source == kScaleFromPrior;
  out.size_m = object_shape * scale;
  // Runs of frames without a gap over max_gap_frames, each fitted once.
  size_t begin = 0;
  while (begin < lifted.size()) {
    size_t end = begin + 1;
    while (end < lifted.size() && lifted[end].frame - lifted[end - 1].frame - 1 <= config.max_gap_frames) {
      ++end;
    }
    const int first = lifted[begin].frame, last = lifted[end - 1].frame;
    std::vector<TrackFrame> frames(last - first + 1);
    for (size_t i = begin; i < end; ++i) {
      const Lifted& l = lifted[i];
      TrackFrame& f = frames[l.frame - first];
      f.keypoints = l.keypoints;
      f.axis_only = out.symmetric && l.lift.degenerate;
      f.start = {Quat(l.unit.R), l.unit.t * scale};
      if (i > begin) {  // interpolate the gap before it
        const int prev = lifted[i - 1].frame;
        for (int g = prev + 1; g < l.frame; ++g) {
          frames[g - first].start = Interpolate(frames[prev - first].start, f.start,
                                                double(g - prev) / (l.frame - prev));
        }
      }
    }
    const std::vector<Pose> poses =
        FitTrackPoses(frames, shape * scale, K, hands.fps > 0 ? hands.fps : 30.0, config.fit);
    for (int k = 0; k <= last - first; ++k) {
      ObjectFrame& f = out.frames[first + k];
      f.posed = true;
      f.pose = poses[k];
      if (out.symmetric) f.pose.q = Quat(CanonicalYaw(f.pose.R()));
      f.filled = !frames[k].keypoints.has_value();
    }
    begin = end;
  }
  return out;
}

}  // namespace

int ObjectTrack::ObservedFrames() const {
  return static_cast<int>(std::count_if(frames.begin(), frames.end(), [](const ObjectFrame& f) { return f.observed; }));
}

int ObjectTrack::PosedFrames() const {
  return static_cast<int>(std::count_if(frames.begin(), frames.end(), [](const ObjectFrame& f) { return f.posed; }));
}

ObjectsResult ReconstructObjects(const std::vector<ObjectObservation>& observations,
                                 const recon::ClipBundle& hands, const ObjectsConfig& config) {
  if (hands.K.empty()) throw Error("bad_bundle", "the hands bundle has no K", {.field = "K"});
  ObjectsResult result;
  std::map<int, std::vector<const ObjectObservation*>> by_track;
  for (const ObjectObservation& o : observations) {
    if (o.frame < 0 || o.frame >= hands.frames) {
      throw Error("bad_keypoints",
                  "observation of frame " + std::to_string(o.frame) + " outside the span's " +
                      std::to_string(hands.frames) + " frames",
                  {.field = "frame"});
    }
    if (o.score < config.min_score) continue;
    if (!FindCategory(o.category)) {
      if (std::find(result.unknown_categories.begin(), result.unknown_categories.end(),
                    o.category) == result.unknown_categories.end()) {
        result.unknown_categories.push_back(o.category);
      }
      continue;
    }
    by_track[o.track].push_back(&o);
  }
  for (auto& [track, obs] : by_track) {
    // One observation per frame (the best scored), in frame order.
    std::sort(obs.begin(), obs.end(), [](const ObjectObservation* a, const ObjectObservation* b) {
      return a->frame != b->frame ? a->frame < b->frame : a->score > b->score;
    });
    obs.erase(std::unique(obs.begin(), obs.end(),
                          [](const ObjectObservation* a, const ObjectObservation* b) {
                            return a->frame == b->frame;
                          }),
              obs.end());
    if (static_cast<int>(obs.size()) < config.min_track_frames) {
      ++result.dropped_short_tracks;
      continue;
    }
    ObjectTrack t = LiftTrack(obs, *FindCategory(obs.front()->category), hands, config);
    CarryWithHands(t, hands, config.carry, config.fingertip_offset_m);
    if (t.PosedFrames() > 0) result.tracks.push_back(std::move(t));
  }
  for (int i = 0; i < static_cast<int>(result.tracks.size()); ++i) {
    const ObjectTrack& t = result.tracks[i];
    if (result.chosen < 0) {
      result.chosen = i;
      continue;
    }
    const ObjectTrack& c = result.tracks[result.chosen];
    if (std::make_pair(t.contact_frames, t.ObservedFrames()) >
        std::make_pair(c.contact_frames, c.ObservedFrames())) {
      result.chosen = i;
    }
  }
  return result;
}

}  // namespace doasido::objects
