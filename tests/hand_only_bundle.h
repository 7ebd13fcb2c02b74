// Hand-only clip bundles for tests: the layout the `hands` stage writes
// into <artifacts>/<clip>/hands/ (meta.json with producers and
// intrinsics_assumed, K.npz, hands.npz; no object, depth or masks), made
// from ground truth until that stage is in:
//   - HandOnlyCopy drops every object and image part of a full (synthetic)
//     bundle, keeping its exact hands, K and gravity;
//   - RealHandBundle moves the real human hand motion of
//     ../shared/data/retarget/human_hand_keypoints_right.csv (metres,
//     wrist-centred) in front of a camera of the given size, optionally
//     with a left hand (the right one mirrored, 20 cm to its left) and a
//     gap of unseen frames.
#pragma once

#include <cmath>
#include <filesystem>
#include <fstream>

#include "recon/bundle/bundle.h"
#include "robot/trajectory/format.h"
#include "tests/test_util.h"

namespace doasido::testing {

inline recon::ClipBundle HandOnlyCopy(const recon::ClipBundle& full) {
  recon::ClipBundle b;
  b.width = full.width;
  b.height = full.height;
  b.frames = full.frames;
  b.fps = full.fps;
  b.K = full.K;
  b.hand_left = full.hand_left;
  b.hand_right = full.hand_right;
  for (auto* hand : {&b.hand_left, &b.hand_right}) {
    if (*hand) {
      (*hand)->verts.clear();
      (*hand)->faces.resize(0, 3);
    }
  }
  b.gravity_up = full.gravity_up;
  b.producers = {{"hands", "test: ground truth standing in for the hands stage"}};
  return b;
}

struct RealHandOptions {
  int frames = 60;
  int width = 640, height = 480;
  double fps = 30;
  bool left = false;          // also a left hand
  int gap_from = -1, gap_to = -1;  // right hand unseen in [gap_from, gap_to)
  int first_keypoint_frame = 0;    // where in the CSV the clip starts
};

inline recon::ClipBundle RealHandBundle(const RealHandOptions& o) {
  static const std::vector<retarget::Keypoints21> csv =
      retarget::ReadKeypointCsv(SharedData() / "retarget/human_hand_keypoints_right.csv");
  recon::ClipBundle b;
  b.width = o.width;
  b.height = o.height;
  b.frames = o.frames;
  b.fps = o.fps;
  const double f = 0.9 * std::max(o.width, o.height);
  Mat3 K;
  K << f, 0, o.width / 2.0, 0, f, o.height / 2.0, 0, 0, 1;
  b.K = {K};
  recon::HandTrack right, left;
  for (int t = 0; t < o.frames; ++t) {
    const retarget::Keypoints21& k = csv[(o.first_keypoint_frame + t) % csv.size()];
    // In front of the camera, drifting sideways a few centimetres.
    const Eigen::RowVector3d at(0.05 + 0.03 * std::sin(t / 20.0), 0.05, 0.45);
    recon::Joints21 r = k.rowwise() + at;
    const bool seen = t < o.gap_from || t >= o.gap_to;
    right.valid.push_back(seen);
    right.joints.push_back(r);
    if (o.left) {
      recon::Joints21 l = k;
      l.col(0) *= -1;
      l.rowwise() += at - Eigen::RowVector3d(0.25, 0, 0);
      left.valid.push_back(true);
      left.joints.push_back(l);
    }
  }
  b.hand_right = right;
  if (o.left) b.hand_left = left;
  b.producers = {{"hands", "test: real keypoints (human_hand_keypoints_right.csv) placed in front of the camera"}};
  return b;
}

// Writes `b` like the hands stage: the bundle plus meta.json's
// intrinsics_assumed.
inline void WriteHandsStageBundle(const recon::ClipBundle& b, const std::filesystem::path& dir,
                                  bool intrinsics_assumed) {
  recon::WriteBundle(b, dir);
  Json meta = Json::parse(ReadFile(dir / "meta.json"));
  meta["intrinsics_assumed"] = intrinsics_assumed;
  WriteFile(dir / "meta.json", meta.dump(2));
}

}  // namespace doasido::testing
