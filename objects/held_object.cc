#include "objects/held_object.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/hand_keypoints.h"

namespace doasido::objects {
namespace {

bool FiniteJoints(const recon::Joints21& j) { return j.allFinite(); }

// The hand of `side` on frame t, when the bundle has it there.
const recon::Joints21* HeldHandAt(const std::optional<recon::HandTrack>& hand, int t) {
  if (!hand || t >= static_cast<int>(hand->valid.size()) || !hand->valid[t] ||
      t >= static_cast<int>(hand->joints.size()) || !FiniteJoints(hand->joints[t])) {
    return nullptr;
  }
  return &hand->joints[t];
}

}  // namespace

Pose HandFrame(const recon::Joints21& joints) {
  const Vec3 wrist = joints.row(kWrist).transpose();
  const Vec3 x = (Vec3(joints.row(kIndexBase).transpose()) - wrist).normalized();
  const Vec3 z = x.cross(Vec3(joints.row(kLittleBase).transpose()) - wrist).normalized();
  Mat3 R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return {Quat(R), wrist};
}

double FingertipToBox(const recon::Joints21& joints, const Pose& box, const Vec3& size) {
  const Pose to_box = box.Inverse();
  const Vec3 half = size / 2;
  double best = std::numeric_limits<double>::infinity();
  for (int k : kFingertips) {
    const Vec3 p = to_box * Vec3(joints.row(k).transpose());
    const Vec3 outside = (p.cwiseAbs() - half).cwiseMax(0.0);
    best = std::min(best, outside.norm());
  }
  return best;
}

int CarryWithHands(ObjectTrack& track, const recon::ClipBundle& hands, const CarryConfig& config,
                   double fingertip_offset_m) {
  const std::optional<recon::HandTrack>* sides[] = {&hands.hand_left, &hands.hand_right};
  struct Grip {
    int side = -1;
    Pose object_in_hand;
    Pose object;    // where it was: where it stays if let go
    int frame = 0;  // the observed frame that set it
  };
  std::optional<Grip> grip;
  const auto holding = [&](int t, const Pose& pose) -> std::optional<Grip> {
    std::optional<Grip> best;
    double nearest = config.hold_distance_m + fingertip_offset_m;
    for (int s = 0; s < 2; ++s) {
      const recon::Joints21* j = HeldHandAt(*sides[s], t);
      if (!j) continue;
      const double d = FingertipToBox(*j, pose, track.size_m);
      if (d <= nearest) {
        nearest = d;
        best = Grip{s, HandFrame(*j).Inverse() * pose, pose, t};
      }
    }
    return best;
  };
  int carried = 0;
  for (int t = 0; t < static_cast<int>(track.frames.size()); ++t) {
    ObjectFrame& f = track.frames[t];
    const bool seen = f.observed && f.posed && !f.filled;
    if (grip && t - grip->frame > config.max_frames) grip.reset();
    const recon::Joints21* hand = grip ? HeldHandAt(*sides[grip->side], t) : nullptr;
    if (grip && !hand) grip.reset();  // the holding hand is not seen: nothing to carry by
    if (grip) {
      const Pose by_hand = HandFrame(*hand) * grip->object_in_hand;
      const double off_hand = (f.pose.t - by_hand.t).norm();
      const double off_rest = (f.pose.t - grip->object.t).norm();
      const std::optional<Grip> touching = seen ? holding(t, f.pose) : std::nullopt;
      if (touching && off_hand <= config.max_deviation_m) {
        grip = touching;  // seen in the hand: its own pose, the grip taken again
        continue;
      }
      if (seen && !touching && off_rest <= config.max_deviation_m && off_rest <= off_hand) {
        grip.reset();  // let go: the object stays where the hand left it
      } else {
        // Unseen, or seen away from the fingers and from where it was: a
        // misreading while the hand holds it.
        f.pose = by_hand;
        f.posed = f.filled = f.carried = true;
        ++carried;
        continue;
      }
    }
    if (seen) grip = holding(t, f.pose);
  }
  return carried;
}

}  // namespace doasido::objects
