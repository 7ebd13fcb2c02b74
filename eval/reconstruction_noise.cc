#include "eval/reconstruction_noise.h"

#include <random>

namespace doasido::synth {

recon::Reconstruction EpisodeReconstruction(const Episode& episode, double fps,
                                            const HandShape& shape) {
  recon::Reconstruction r;
  r.fps = fps;
  bool left_seen = false;
  for (const EpisodeFrame& f : episode.frames) {
    for (const Side side : {Side::kRight, Side::kLeft}) {
      const auto& hand = f.hands[static_cast<int>(side)];
      (side == Side::kRight ? r.right_valid : r.left_valid).push_back(hand.has_value());
      (side == Side::kRight ? r.right_joints : r.left_joints)
          .push_back(hand ? HandJointPositions(*hand, side, shape) : recon::Joints21::Constant(std::nan("")));
      left_seen |= side == Side::kLeft && hand.has_value();
    }
    r.object_valid.push_back(true);
    r.object_poses.push_back(f.object_pose);
  }
  if (!left_seen) {
    r.left_valid.clear();
    r.left_joints.clear();
  }
  return r;
}

void AddReconstructionNoise(recon::Reconstruction& r, const ReconstructionNoise& noise,
                            std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0, 1);
  const auto gauss3 = [&](double sd) { return Vec3(sd * n(rng), sd * n(rng), sd * n(rng)); };
  const double scale = 1 + noise.depth_scale * n(rng);
  const Vec3 offset = gauss3(noise.misalignment);
  const int frames = r.frames();
  const int jump_frame = frames > 2 ? std::uniform_int_distribution<int>(frames / 3, 2 * frames / 3)(rng) : frames;
  const Vec3 jump = gauss3(1.0).normalized() * noise.discontinuity;
  const auto scaled = [&](const Vec3& p) { return Vec3(noise.camera + scale * (p - noise.camera)); };
  const double lift = r.object_poses.empty() ? 0.0 : r.object_poses[0].t.z() - scaled(r.object_poses[0].t).z();
  for (int t = 0; t < frames; ++t) {
    const Vec3 shift = Vec3(0, 0, lift) + (t >= jump_frame ? jump : Vec3::Zero());
    for (auto* hand : {&r.right_joints, &r.left_joints}) {
      const std::vector<bool>& valid = hand == &r.right_joints ? r.right_valid : r.left_valid;
      if (hand->empty() || !valid[t]) continue;
      for (int k = 0; k < 21; ++k) {
        const Vec3 p = (*hand)[t].row(k).transpose();
        (*hand)[t].row(k) = (scaled(p) + shift + offset + gauss3(noise.jitter)).transpose();
      }
    }
    if (r.object_valid[t]) {
      Pose& o = r.object_poses[t];
      o.t = scaled(o.t) + shift + gauss3(noise.jitter);
      const Vec3 w = gauss3(noise.jitter_rot);
      if (w.norm() > 0) o.q = (Quat(Eigen::AngleAxisd(w.norm(), w.normalized())) * o.q).normalized();
    }
  }
}

}  // namespace doasido::synth
