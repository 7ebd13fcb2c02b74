#include "synth/episode.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "core/error.h"
#include "synth/objects.h"

namespace doasido::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTouchTol = 0.001;  // metres of clearance that count as touching

// Distance queries against a posed object with a bounding-sphere early out.
class Proximity {
 public:
  explicit Proximity(TriMesh mesh) : mesh_(std::move(mesh)) {
    centre_ = 0.5 * (mesh_.Min() + mesh_.Max());
    radius_ = 0;
    for (int i = 0; i < mesh_.num_vertices(); ++i) {
      radius_ = std::max(radius_, (Vec3(mesh_.vertices.row(i).transpose()) - centre_).norm());
    }
  }
  // Lower bound on the distance when far away, exact when near.
  double Distance(const Vec3& p, double near) const {
    const double bound = (p - centre_).norm() - radius_;
    if (bound > near) return bound;
    return DistanceToMesh(mesh_, p);
  }
  double radius() const { return radius_; }
  const Vec3& centre() const { return centre_; }

 private:
  TriMesh mesh_;
  Vec3 centre_;
  double radius_;
};

// Smallest (distance - radius) over points sampled along the capsules.
double Clearance(const std::vector<Capsule>& caps, int first, int last, const Proximity& obj) {
  double best = std::numeric_limits<double>::infinity();
  for (int c = first; c < last; ++c) {
    for (int k = 0; k <= 4; ++k) {
      const Vec3 p = caps[c].a + (caps[c].b - caps[c].a) * (k / 4.0);
      best = std::min(best, obj.Distance(p, caps[c].radius + 0.01) - caps[c].radius);
    }
  }
  return best;
}

HandPose WithCurl(const Pose& wrist, const std::array<double, 5>& curl) {
  HandPose p = RelaxedPose(wrist);
  for (int f = 0; f < 5; ++f) SetFingerCurl(p, f, curl[f]);
  return p;
}

// The hand of grasp `g` closed by s in [0, 1]: open at 0, gripping at 1.
HandPose Closed(const Pose& wrist, const Grasp& g, double s) {
  std::array<double, 5> curl;
  for (int f = 0; f < 5; ++f) curl[f] = g.open[f] + (g.curl[f] - g.open[f]) * s;
  return WithCurl(wrist, curl);
}

// Closes each finger f of `g` from its curl until its capsules touch the
// object (bisection; `touching` set) or it is fully curled; fingers in turn,
// thumb first, each with the ones before it already closed.
// `capsules_at(curl)` poses the hand at curls `curl`.
template <class CapsulesAt>
void CloseFingers(Grasp& g, const CapsulesAt& capsules_at, const Proximity& obj) {
  for (int f = 0; f < 5; ++f) {
    if (g.touching[f]) continue;
    auto clearance = [&](double c) {
      std::array<double, 5> curl = g.curl;
      curl[f] = c;
      return Clearance(capsules_at(curl), 3 * f, 3 * f + 3, obj);
    };
    const double start = g.curl[f];
    double lo = start, hi = -1;
    for (double c = start; c <= 1.0 + 1e-9; c += 0.04) {
      if (clearance(c) <= kTouchTol) {
        hi = c;
        break;
      }
      lo = c;
    }
    if (hi < 0) {
      g.curl[f] = std::max(start, 1.0);
      continue;
    }
    g.touching[f] = true;
    if (hi == start) continue;
    for (int it = 0; it < 10; ++it) {
      const double mid = 0.5 * (lo + hi);
      (clearance(mid) <= kTouchTol ? hi : lo) = mid;
    }
    g.curl[f] = hi;
  }
}

Vec3 ApproachDirection(Side side, double azimuth, double elevation) {
  const double sx = side == Side::kRight ? 1.0 : -1.0;
  return Vec3(sx * std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
              std::sin(elevation));
}

Mat3 GraspFrame(Side side, const Vec3& a) {
  const Vec3 n = -a;
  const Vec3 r = (Vec3::UnitZ() - Vec3::UnitZ().dot(n) * n).normalized();
  const Vec3 d = side == Side::kRight ? n.cross(r) : r.cross(n);
  return HandFrame(d, n);
}

Pose RestPose(const EpisodeSpec& spec) {
  return {Quat(Eigen::AngleAxisd(spec.object_yaw, Vec3::UnitZ())),
          Vec3(spec.object_xy.x(), spec.object_xy.y(), 0)};
}

Pose Translated(const Pose& p, const Vec3& d) { return {p.q, p.t + d}; }

Pose Interpolate(const Pose& a, const Pose& b, double s) {
  return {a.q.slerp(s, b.q), a.t + (b.t - a.t) * s};
}

double Seg(double f, double a, double b) { return std::clamp((f - a) / (b - a), 0.0, 1.0); }

// Object pose during manipulation, u in [0, 1]; starts at `rest`.
Pose VerbPose(Verb verb, const Pose& rest, double height, double side_sign, double scale,
              double u) {
  switch (verb) {
    case Verb::kPickPlace: {
      const Vec3 target(-side_sign * 0.12 * scale, 0.04 * scale, 0);
      const double lift = 0.08 * scale * (MinJerk(Seg(u, 0, 0.3)) - MinJerk(Seg(u, 0.7, 1)));
      const Vec3 move = target * MinJerk(Seg(u, 0.3, 0.7));
      return Translated(rest, move + Vec3(0, 0, lift));
    }
    case Verb::kLiftRotate: {
      const double lift = 0.10 * scale * (MinJerk(Seg(u, 0, 0.25)) - MinJerk(Seg(u, 0.75, 1)));
      const double tilt =
          -side_sign * 1.2 * (MinJerk(Seg(u, 0.25, 0.5)) - MinJerk(Seg(u, 0.5, 0.75)));
      const Vec3 pivot = rest.t + Vec3(0, 0, height / 2 + lift);
      const Quat r(Eigen::AngleAxisd(tilt, Vec3::UnitY()));
      // Rotate about the object's centre, then lift.
      const Vec3 base = rest.t + Vec3(0, 0, lift);
      return {r * rest.q, pivot + r * (base - pivot)};
    }
    case Verb::kSlide: {
      const double x = 0.08 * scale * std::sin(2 * kPi * 2 * MinJerk(u)) * side_sign;
      const double y = 0.02 * scale * (1 - std::cos(2 * kPi * MinJerk(u)));
      return Translated(rest, Vec3(x, y, 0));
    }
    case Verb::kStir: {
      const double a = 2 * kPi * 1.5 * MinJerk(u);
      const double r = 0.05 * scale;
      return Translated(rest, Vec3(side_sign * r * (std::cos(a) - 1), r * std::sin(a), 0));
    }
  }
  return rest;
}

// Closing s in [0, 1] takes the pinch's opening from ~10 cm to ~4 cm.
std::array<double, 5> PinchPosture(double s) {
  const double f = -0.1 + 0.5 * s;
  return {0.3 + 0.2 * s, f, f, f, f};
}

// Where a pinching hand goes (SolvePinchGrasp): the opening (thumb tip to
// the index and middle tips) laid along `across` (horizontal, across the
// approach `a`), its midpoint at `centre` + shift * across + back_off * a,
// the wrist on the approach side, the radial side up.
class PinchPlacement {
 public:
  PinchPlacement(Side side, const HandShape& shape, const Proximity& obj, const Vec3& a,
                 const Vec3& centre)
      : side_(side), shape_(shape), obj_(obj), a_(a), centre_(centre),
        across_(Vec3(a.x(), a.y(), 0).cross(Vec3::UnitZ()).normalized()) {
    const auto open = PinchPosture(0);
    double up = 1;
    for (double s : {1.0, -1.0}) {
      sign_ = s;
      const HandJoints j = HandJointPositions(WithCurl(Wrist(open), open), side_, shape_);
      if (j(1, 2) > j(17, 2)) up = s;  // the thumb's base above the little finger's
    }
    sign_ = up;
  }

  Pose Wrist(const std::array<double, 5>& curl) const {
    const HandJoints j = HandJointPositions(WithCurl(Pose{}, curl), side_, shape_);
    const Vec3 thumb = j.row(4).transpose(), fingers = 0.5 * (j.row(8) + j.row(12)).transpose();
    const Vec3 mid = 0.5 * (thumb + fingers), e = (fingers - thumb).normalized();
    const Vec3 back = (-mid - (-mid).dot(e) * e).normalized();
    Mat3 local, world;
    local << e, back, e.cross(back);
    const Vec3 u = sign_ * across_;
    world << u, a_, u.cross(a_);
    const Mat3 R = world * local.transpose();
    return Pose{Quat(R), centre_ + shift_ * across_ + back_off_ * a_ - R * mid};
  }

  std::vector<Capsule> Capsules(const std::array<double, 5>& curl, const Pose& wrist) const {
    const HandPose hp = WithCurl(wrist, curl);
    return HandCapsules(HandJointPositions(hp, side_, shape_), hp, side_, shape_);
  }

  // An object too wide for the open hand: backs the hand off along the
  // approach until it fits. Then closes until the first touch, slides the
  // hand across until the thumb and the fingers are equally far from the
  // surface, and again. Returns the closing s at the touch.
  double Close() {
    while (Touching(0) && back_off_ < 0.04) back_off_ += 0.002;
    double hi = 1;
    for (int round = 0; round < 6; ++round) {
      double lo = 0;
      hi = 1;
      for (int it = 0; it < 14; ++it) {
        const double mid = 0.5 * (lo + hi);
        (Touching(mid) ? hi : lo) = mid;
      }
      if (round == 5) break;
      const auto c = Capsules(PinchPosture(hi), Wrist(PinchPosture(hi)));
      shift_ += sign_ * 0.5 * (Clearance(c, 0, 3, obj_) - Clearance(c, 3, 9, obj_));
    }
    return hi;
  }

 private:
  bool Touching(double s) const {
    const auto c = Capsules(PinchPosture(s), Wrist(PinchPosture(s)));
    return Clearance(c, 0, static_cast<int>(c.size()), obj_) <= kTouchTol;
  }

  Side side_;
  const HandShape& shape_;
  const Proximity& obj_;
  Vec3 a_, centre_, across_;
  double sign_ = 1, shift_ = 0, back_off_ = 0;
};

// Carrying the object out of view and back (for LeaveFrame::kObject).
Pose CarryOutPose(const Pose& rest, double side_sign, double u) {
  const double lift = 0.12 * (MinJerk(Seg(u, 0, 0.1)) - MinJerk(Seg(u, 0.87, 1)));
  const double out = 0.9 * (MinJerk(Seg(u, 0.1, 0.32)) - MinJerk(Seg(u, 0.6, 0.87)));
  return Translated(rest, Vec3(side_sign * out, 0, lift));
}

}  // namespace

const char* VerbName(Verb verb) {
  switch (verb) {
    case Verb::kPickPlace:
      return "pick_place";
    case Verb::kLiftRotate:
      return "lift_rotate";
    case Verb::kSlide:
      return "slide";
    case Verb::kStir:
      return "stir";
  }
  return "unknown";
}

double MinJerk(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * t * (10 - 15 * t + 6 * t * t);
}

Grasp SolveGrasp(const TriMesh& object, Side side, double azimuth, double elevation,
                 double object_yaw, const HandShape& shape) {
  const Pose rest{Quat(Eigen::AngleAxisd(object_yaw, Vec3::UnitZ())), Vec3::Zero()};
  const Proximity obj(object.Transformed(rest));
  const double height = object.Max().z();
  const Vec3 target(0, 0, std::min(0.55 * height, 0.07));
  const Vec3 a = ApproachDirection(side, azimuth, elevation);
  const Mat3 R = GraspFrame(side, a);
  const Vec3 palm_local(0, 0.05 * shape.scale, 0);

  auto posed = [&](double dist, const std::array<double, 5>& curl) {
    const Vec3 palm = target + a * dist;
    const Pose wrist{Quat(R), palm - R * palm_local};
    const HandPose hp = WithCurl(wrist, curl);
    const HandJoints j = HandJointPositions(hp, side, shape);
    return std::make_pair(hp, HandCapsules(j, hp, side, shape));
  };
  // Move the open hand in along -a until it first touches.
  std::array<double, 5> open{};
  const int n_caps = static_cast<int>(posed(1.0, open).second.size());
  double far = obj.radius() + 0.15, near = 0.0;
  auto touching = [&](double dist) {
    return Clearance(posed(dist, open).second, 0, n_caps, obj) <= kTouchTol;
  };
  double step_hi = far;
  for (double d = far; d >= 0; d -= 0.005) {
    if (touching(d)) {
      near = d;
      break;
    }
    step_hi = d;
  }
  for (int it = 0; it < 12; ++it) {  // boundary between touching (near) and free (step_hi)
    const double mid = 0.5 * (near + step_hi);
    (touching(mid) ? near : step_hi) = mid;
  }
  const double dist = step_hi + 0.002;
  Grasp g;
  g.curl.fill(0.0);
  CloseFingers(g, [&](const std::array<double, 5>& curl) { return posed(dist, curl).second; }, obj);
  const Pose wrist = posed(dist, g.curl).first.wrist;
  g.wrist_in_object = rest.Inverse() * wrist;
  return g;
}

Grasp SolvePinchGrasp(const TriMesh& object, Side side, double azimuth, double elevation,
                      double object_yaw, const HandShape& shape) {
  const Pose rest{Quat(Eigen::AngleAxisd(object_yaw, Vec3::UnitZ())), Vec3::Zero()};
  const Proximity obj(object.Transformed(rest));
  PinchPlacement p(side, shape, obj, ApproachDirection(side, azimuth, elevation),
                   Vec3(0, 0, std::min(0.55 * object.Max().z(), 0.07)));
  Grasp g;
  g.curl = PinchPosture(p.Close());
  const Pose wrist = p.Wrist(g.curl);
  const auto c = p.Capsules(g.curl, wrist);
  for (int f = 0; f < 3; ++f) g.touching[f] = Clearance(c, 3 * f, 3 * f + 3, obj) <= 2 * kTouchTol;
  // The ring and little fingers tuck in, off the object: pressing on its
  // side across the pinch, they would push it out.
  for (int f = 3; f < 5; ++f) {
    std::array<double, 5> curl = g.curl;
    curl[f] = 1.0;
    if (Clearance(p.Capsules(curl, wrist), 3 * f, 3 * f + 3, obj) > kTouchTol) g.curl[f] = 1.0;
  }
  CloseFingers(g, [&](const std::array<double, 5>& curl) { return p.Capsules(curl, wrist); }, obj);
  // The approach and the release: the thumb at its grip (it comes to rest
  // on the surface as the hand arrives), index and middle opened wider than
  // the widest pinch, the others tucked as they grip.
  g.open = {g.curl[0], -0.15, -0.15, g.curl[3], g.curl[4]};
  g.wrist_in_object = rest.Inverse() * wrist;
  return g;
}

namespace {

// One hand's grasp of the object and the poses around it.
struct HandPlan {
  Grasp grasp;
  Vec3 a;  // approach direction (world)
  Pose At(const Pose& object_pose) const { return object_pose * grasp.wrist_in_object; }
  // Backed off along the approach by `far` (and raised 4 cm when far).
  Pose Back(const Pose& object_pose, double far) const {
    return Translated(At(object_pose), a * far + Vec3(0, 0, far > 0.1 ? 0.04 : 0));
  }
  // Reach from far away to the grasp over [u0, u1] (60% of it to 6 cm off).
  Pose Reach(const Pose& object_pose, double u, double u0, double u1) const {
    const double mid = u0 + 0.6 * (u1 - u0);
    return u <= mid ? Interpolate(Back(object_pose, 0.16), Back(object_pose, 0.06), MinJerk(Seg(u, u0, mid)))
                    : Interpolate(Back(object_pose, 0.06), At(object_pose), MinJerk(Seg(u, mid, u1)));
  }
};

Grasp SolveGraspOfType(GraspType type, const TriMesh& object, Side side, double azimuth,
                       double elevation, double yaw, const HandShape& shape) {
  return type == GraspType::kPinch ? SolvePinchGrasp(object, side, azimuth, elevation, yaw, shape)
                                   : SolveGrasp(object, side, azimuth, elevation, yaw, shape);
}

HandPlan PlanHand(GraspType type, const TriMesh& object, Side side, double azimuth, double elevation,
                  double yaw, const HandShape& shape) {
  return {SolveGraspOfType(type, object, side, azimuth, elevation, yaw, shape),
          ApproachDirection(side, azimuth, elevation)};
}

// Curl closing over [c0, c1], open until c0, closed until o0, opening over [o0, o1].
double Closing(double u, double c0, double c1, double o0, double o1) {
  return u <= o0 ? MinJerk(Seg(u, c0, c1)) : 1 - MinJerk(Seg(u, o0, o1));
}

}  // namespace

const char* GraspTypeName(GraspType type) {
  return type == GraspType::kPinch ? "pinch" : "wrap";
}

GraspType GraspTypeFromName(const std::string& name) {
  for (const GraspType t : {GraspType::kWrap, GraspType::kPinch}) {
    if (name == GraspTypeName(t)) return t;
  }
  throw Error("bad_config", "grasp must be wrap or pinch, not '" + name + "'", {.field = "grasp"});
}

const char* TwoHandTaskName(TwoHandTask task) {
  switch (task) {
    case TwoHandTask::kNone:
      return "none";
    case TwoHandTask::kHandover:
      return "handover";
    case TwoHandTask::kCarry:
      return "carry";
    case TwoHandTask::kHoldAndAct:
      return "hold_and_act";
  }
  return "unknown";
}

TwoHandTask TwoHandTaskFromName(const std::string& name) {
  for (const TwoHandTask t : {TwoHandTask::kNone, TwoHandTask::kHandover, TwoHandTask::kCarry, TwoHandTask::kHoldAndAct}) {
    if (name == TwoHandTaskName(t)) return t;
  }
  throw Error("bad_config", "two_hand_task must be none, handover, carry or hold_and_act, not '" + name + "'",
              {.field = "two_hand_task"});
}

namespace {

// Where each hand's wrist is, how far its fingers are closed (0-1) and
// whether it touches the object, at one frame of a two-hand script.
struct TwoHandFrame {
  Pose right, left;
  double right_curl = 0, left_curl = 0;
  bool right_touch = false, left_touch = false;
};

// The right hand lifts the object and offers it; the left takes it over and
// puts it down (u in [0, 1] through the clip; sets the object's pose and the
// phase in `fr`).
TwoHandFrame HandoverFrame(double u, const Pose& rest, const HandPlan& right, const HandPlan& left,
                           EpisodeFrame& fr) {
  TwoHandFrame w;
  const Pose offer = Translated(rest, Vec3(-0.08, 0, 0.12));
  const Pose placed = Translated(rest, Vec3(-0.22, 0.02, 0));
  fr.object_pose = u <= 0.24   ? rest
                   : u <= 0.44 ? Interpolate(rest, offer, MinJerk(Seg(u, 0.24, 0.44)))
                   : u <= 0.66 ? offer
                               : Interpolate(offer, placed, MinJerk(Seg(u, 0.66, 0.86)));
  w.right = u <= 0.18   ? right.Reach(rest, u, 0, 0.18)
            : u <= 0.66 ? right.At(fr.object_pose)
                        : Interpolate(right.At(offer), right.Back(offer, 0.16),
                                      MinJerk(Seg(u, 0.66, 0.80)));
  w.right_curl = u <= 0.66 ? Closing(u, 0.18, 0.24, 0.60, 0.66) : 0;
  w.left = u <= 0.30   ? left.Back(offer, 0.16)
           : u <= 0.50 ? left.Reach(offer, u, 0.30, 0.50)
           : u <= 0.92
               ? left.At(fr.object_pose)
               : Interpolate(left.At(placed), left.Back(placed, 0.16), MinJerk(Seg(u, 0.92, 1.0)));
  w.left_curl = u > 0.50 && u <= 0.92 ? Closing(u, 0.50, 0.56, 0.86, 0.92) : 0;
  w.right_touch = u >= 0.24 && u < 0.60;
  w.left_touch = u >= 0.56 && u < 0.86;
  fr.phase = u < 0.24   ? "reach"
             : u < 0.44 ? "carry"
             : u < 0.56 ? "offer"
             : u < 0.66 ? "handover"
             : u < 0.86 ? "carry"
                        : "release";
  return w;
}

// Both hands lift the object together, carry it and put it down.
TwoHandFrame CarryFrame(double u, const Pose& rest, const HandPlan& right, const HandPlan& left,
                        EpisodeFrame& fr) {
  TwoHandFrame w;
  const Pose up = Translated(rest, Vec3(0.05, 0.05, 0.15));
  const Pose down = Translated(rest, Vec3(0.10, 0.05, 0));
  fr.object_pose = u <= 0.24   ? rest
                   : u <= 0.50 ? Interpolate(rest, up, MinJerk(Seg(u, 0.24, 0.50)))
                   : u <= 0.76 ? Interpolate(up, down, MinJerk(Seg(u, 0.50, 0.76)))
                               : down;
  for (const auto& [hand, wrist, curl] :
       {std::tie(right, w.right, w.right_curl), std::tie(left, w.left, w.left_curl)}) {
    wrist = u <= 0.18 ? hand.Reach(rest, u, 0, 0.18)
            : u <= 0.82
                ? hand.At(fr.object_pose)
                : Interpolate(hand.At(down), hand.Back(down, 0.16), MinJerk(Seg(u, 0.82, 1.0)));
    curl = u <= 0.82 ? Closing(u, 0.18, 0.24, 0.76, 0.82) : 0;
  }
  w.right_touch = w.left_touch = u >= 0.24 && u < 0.76;
  fr.phase = u < 0.24 ? "reach" : u < 0.76 ? "carry" : "release";
  return w;
}

// The left hand holds the object still while the right twists it.
TwoHandFrame HoldAndActFrame(double u, const Pose& rest, const HandPlan& right,
                             const HandPlan& left, EpisodeFrame& fr) {
  TwoHandFrame w;
  fr.object_pose = rest;
  w.left = u <= 0.18 ? left.Reach(rest, u, 0, 0.18)
           : u <= 0.92
               ? left.At(rest)
               : Interpolate(left.At(rest), left.Back(rest, 0.16), MinJerk(Seg(u, 0.92, 1.0)));
  w.left_curl = u <= 0.92 ? Closing(u, 0.18, 0.24, 0.86, 0.92) : 0;
  // Twisting about the object's own vertical axis keeps a round object's surface under the fingers.
  const double twist =
      u > 0.48 && u < 0.76 ? 0.4 * std::sin(2 * kPi * 2 * Seg(u, 0.48, 0.76)) : 0.0;
  const Pose turned = rest * Pose{Quat(Eigen::AngleAxisd(twist, Vec3::UnitZ())), Vec3::Zero()};
  w.right = u <= 0.24   ? right.Back(rest, 0.16)
            : u <= 0.42 ? right.Reach(rest, u, 0.24, 0.42)
            : u <= 0.82
                ? right.At(turned)
                : Interpolate(right.At(rest), right.Back(rest, 0.16), MinJerk(Seg(u, 0.82, 1.0)));
  w.right_curl = u > 0.42 && u <= 0.82 ? Closing(u, 0.42, 0.48, 0.76, 0.82) : 0;
  w.left_touch = u >= 0.24 && u < 0.86;
  w.right_touch = u >= 0.48 && u < 0.76;
  fr.phase = u < 0.24 ? "reach" : u < 0.48 ? "steady" : u < 0.76 ? "act" : "release";
  return w;
}

}  // namespace

Episode ScriptTwoHands(const EpisodeSpec& spec, const TriMesh& object, const HandShape& shape) {
  Episode ep;
  ep.spec = spec;
  const Pose rest = RestPose(spec);
  const HandPlan left = PlanHand(spec.grasp, object, Side::kLeft, spec.approach_azimuth, spec.approach_elevation,
                                 spec.object_yaw, shape);
  const double right_elevation =
      spec.two_hand_task == TwoHandTask::kHoldAndAct ? kPi / 2 - 0.2 : spec.approach_elevation;
  const HandPlan right = PlanHand(spec.grasp, object, Side::kRight, spec.approach_azimuth, right_elevation, spec.object_yaw, shape);
  ep.grasp = right.grasp;
  const double T = std::max(spec.frames - 1, 1);
  for (int i = 0; i < spec.frames; ++i) {
    const double u = i / T;
    EpisodeFrame fr;
    TwoHandFrame w;
    switch (spec.two_hand_task) {
      case TwoHandTask::kHandover: w = HandoverFrame(u, rest, right, left, fr); break;
      case TwoHandTask::kCarry: w = CarryFrame(u, rest, right, left, fr); break;
      case TwoHandTask::kHoldAndAct: w = HoldAndActFrame(u, rest, right, left, fr); break;
      case TwoHandTask::kNone:
        throw std::logic_error("ScriptTwoHands needs a two-hand task");
    }
    fr.hands[static_cast<int>(Side::kRight)] = Closed(w.right, right.grasp, w.right_curl);
    fr.hands[static_cast<int>(Side::kLeft)] = Closed(w.left, left.grasp, w.left_curl);
    fr.contact[static_cast<int>(Side::kRight)] = w.right_touch;
    fr.contact[static_cast<int>(Side::kLeft)] = w.left_touch;
    ep.frames.push_back(std::move(fr));
  }
  return ep;
}

namespace {

// What every frame of a one-hand script shares: the clip's spec, the grasp
// and the poses the wrist moves between.
struct OneHandScript {
  const EpisodeSpec& spec;
  const Grasp& grasp;
  Pose rest;       // the object at rest
  double height;   // the object's top
  Vec3 a;          // approach direction
  double sx;       // +1 right hand, -1 left
  Pose g0;         // the wrist holding the object at rest
  Pose pre, start, hover, away;
  double T;        // the last frame (at least 1)
};

// One frame of the active hand.
struct WristFrame {
  Pose wrist;
  double curl = 0;
  bool contact = false;
};

OneHandScript MakeOneHandScript(const EpisodeSpec& spec, const TriMesh& object,
                                const Grasp& grasp) {
  const Side side = spec.active;
  const Pose rest = RestPose(spec);
  const Pose rest_xy{Quat::Identity(), rest.t};  // grasp is relative to the yawed object
  const Vec3 a = ApproachDirection(side, spec.approach_azimuth, spec.approach_elevation);
  // The grasp was solved with the object yawed at the origin.
  const Pose g0 = rest_xy *
                  Pose{Quat(Eigen::AngleAxisd(spec.object_yaw, Vec3::UnitZ())), Vec3::Zero()} *
                  grasp.wrist_in_object;
  const double sx = side == Side::kRight ? 1.0 : -1.0;
  return {spec,
          grasp,
          rest,
          object.Max().z(),
          a,
          sx,
          g0,
          Translated(g0, a * 0.06),
          Translated(g0, a * 0.16 + Vec3(0, 0, 0.04)),
          Translated(g0, a * 0.035),
          Translated(g0, Vec3(sx * 0.9, 0, 0.15)),
          static_cast<double>(std::max(spec.frames - 1, 1))};
}

// A clip without touch: reach to hover beside the object, sway, retract.
WristFrame HoverFrame(const OneHandScript& s, double f, EpisodeFrame& fr) {
  const double T = s.T;
  WristFrame out;
  if (f <= 0.3 * T) {
    out.wrist = Interpolate(s.start, s.hover, MinJerk(Seg(f, 0, 0.3 * T)));
    fr.phase = "reach";
  } else if (f <= 0.75 * T) {
    const double w = std::sin(2 * kPi * (f - 0.3 * T) / (0.45 * T));
    out.wrist = Translated(s.hover, Vec3(0, 0.008 * w, 0.004 * w));
    fr.phase = "hover";
  } else {
    out.wrist = Interpolate(s.hover, s.start, MinJerk(Seg(f, 0.75 * T, T)));
    fr.phase = "retract";
  }
  return out;
}

// After the release of a touching clip, from the object's final pose:
// the hand leaves the frame and returns, or retracts.
Pose AfterRelease(const OneHandScript& s, double f, const Pose& g1, double b_open,
                  EpisodeFrame& fr) {
  const double T = s.T;
  const Pose pre1 = Translated(g1, s.a * 0.06);
  const Pose start1 = Translated(g1, s.a * 0.16 + Vec3(0, 0, 0.04));
  if (s.spec.leave == LeaveFrame::kHand) {
    const Pose away1 = Translated(g1, s.away.t - s.g0.t);
    if (f <= 0.65 * T) {
      fr.phase = "exit";
      return Interpolate(g1, away1, MinJerk(Seg(f, b_open * T, 0.65 * T)));
    }
    if (f <= 0.80 * T) {
      fr.phase = "away";
      return away1;
    }
    fr.phase = "return";
    return Interpolate(away1, start1, MinJerk(Seg(f, 0.80 * T, T)));
  }
  const double r = Seg(f, b_open * T, T);
  fr.phase = "retract";
  return r < 0.4 ? Interpolate(g1, pre1, MinJerk(r / 0.4))
                 : Interpolate(pre1, start1, MinJerk((r - 0.4) / 0.6));
}

// A touching clip: reach, approach, grasp, manipulate the object, release.
WristFrame TouchFrame(const OneHandScript& s, double f, EpisodeFrame& fr) {
  const EpisodeSpec& spec = s.spec;
  const double T = s.T;
  // Phase boundaries as fractions of the clip.
  double b_reach = 0.20, b_appr = 0.30, b_close = 0.38, b_manip = 0.78, b_open = 0.86;
  if (spec.leave == LeaveFrame::kHand) {
    b_reach = 0.14, b_appr = 0.20, b_close = 0.26, b_manip = 0.50, b_open = 0.55;
  } else if (spec.leave == LeaveFrame::kObject) {
    b_reach = 0.14, b_appr = 0.20, b_close = 0.26, b_manip = 0.86, b_open = 0.92;
  }
  auto object_at = [&](double u) {
    return spec.leave == LeaveFrame::kObject
               ? CarryOutPose(s.rest, s.sx, u)
               : VerbPose(spec.verb, s.rest, s.height, s.sx, spec.manipulation_scale, u);
  };
  auto grasp_at = [&](const Pose& object_pose) { return object_pose * s.grasp.wrist_in_object; };
  const Pose final_object = object_at(1.0);
  const Pose g1 = grasp_at(final_object);
  WristFrame out;
  if (f <= b_reach * T) {
    out.wrist = Interpolate(s.start, s.pre, MinJerk(Seg(f, 0, b_reach * T)));
    fr.phase = "reach";
  } else if (f <= b_appr * T) {
    out.wrist = Interpolate(s.pre, s.g0, MinJerk(Seg(f, b_reach * T, b_appr * T)));
    fr.phase = "approach";
  } else if (f < b_close * T) {
    out.wrist = s.g0;
    out.curl = MinJerk(Seg(f, b_appr * T, b_close * T));
    fr.phase = "grasp";
  } else if (f <= b_manip * T) {
    fr.object_pose = object_at(Seg(f, b_close * T, b_manip * T));
    out.wrist = grasp_at(fr.object_pose);
    out.curl = 1;
    out.contact = true;
    fr.phase = "manipulate";
  } else {
    fr.object_pose = final_object;
    const double open_s = Seg(f, b_manip * T, b_open * T);
    out.curl = 1 - MinJerk(open_s);
    out.contact = open_s <= 0.0;
    if (f <= b_open * T) {
      out.wrist = g1;
      fr.phase = "release";
    } else {
      out.wrist = AfterRelease(s, f, g1, b_open, fr);
    }
  }
  return out;
}

// The idle hand of a two-hand clip: relaxed beside the object, drifting.
HandPose IdleHand(const OneHandScript& s, double f) {
  const double drift = s.spec.static_scene ? 0.0 : std::sin(2 * kPi * 1.3 * f / s.T);
  const Vec3 pos(s.rest.t.x() - s.sx * s.spec.second_hand_offset + 0.01 * drift,
                 s.rest.t.y() - 0.06, 0.045);
  const Vec3 d = Vec3(s.sx * 0.35, 1, 0).normalized();
  return RelaxedPose(Pose{Quat(HandFrame(d, -Vec3::UnitZ())), pos});
}

}  // namespace

Episode ScriptEpisode(const EpisodeSpec& spec, const TriMesh& object, const HandShape& shape) {
  if (spec.two_hand_task != TwoHandTask::kNone) return ScriptTwoHands(spec, object, shape);
  Episode ep;
  ep.spec = spec;
  const Side side = spec.active;
  const int s_idx = static_cast<int>(side);
  ep.grasp = SolveGraspOfType(spec.grasp, object, side, spec.approach_azimuth, spec.approach_elevation,
                              spec.object_yaw, shape);
  const OneHandScript script = MakeOneHandScript(spec, object, ep.grasp);
  for (int i = 0; i < spec.frames; ++i) {
    const double f = i;
    EpisodeFrame fr;
    fr.object_pose = script.rest;
    WristFrame hand;
    if (spec.static_scene) {
      hand.wrist = Translated(script.g0, script.a * 0.05);
      fr.phase = "static";
    } else {
      hand = spec.touch ? TouchFrame(script, f, fr) : HoverFrame(script, f, fr);
    }
    fr.hands[s_idx] = Closed(hand.wrist, ep.grasp, hand.curl);
    fr.contact[s_idx] = hand.contact;
    if (spec.two_hands) {
      const Side other = side == Side::kRight ? Side::kLeft : Side::kRight;
      fr.hands[static_cast<int>(other)] = IdleHand(script, f);
    }
    ep.frames.push_back(std::move(fr));
  }
  return ep;
}

}  // namespace doasido::synth
