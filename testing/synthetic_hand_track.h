// A hand moving in front of a pinhole camera with exact answers, for the
// hands module's tests and bench: the shape and finger motion are the real
// right hand of ../shared/data/retarget/human_hand_keypoints_right.csv
// (wrist-centred metres, one row per frame; bones held at the first
// row's lengths), turned and carried along a
// smooth path in the camera frame; observations are its projection plus
// pixel noise and "model" 3D landmarks (the hand about its centroid, in a
// fixed arbitrary frame, plus noise), as the landmark model gives them.
#pragma once

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "hands/hand_observation.h"
#include "hands/hand_skeleton_fit.h"

namespace doasido::testing {

struct SyntheticHand {
  Mat3 K;
  int width = 640, height = 480;
  double fps = 30;
  std::vector<hands::Joints> truth;  // camera frame
  std::vector<hands::HandObservation> seen;
};

// Rows of the dex-retargeting keypoint CSV (21 x xyz per row).
inline std::vector<hands::Joints> ReadDexKeypoints(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  std::vector<hands::Joints> rows;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    hands::Joints j;
    std::string cell;
    for (int k = 0; k < 63 && std::getline(s, cell, ','); ++k) j[k / 3][k % 3] = std::stod(cell);
    rows.push_back(j);
  }
  return rows;
}

// `frames` frames from CSV row `first_row`, pixel noise `px` (sigma),
// 3D landmark noise `world_m` (sigma), p_right of every observation, focal
// length `fx` (640 x 480 pixels; 500 is a 65 degree field of view).
inline SyntheticHand MakeSyntheticHand(const std::vector<hands::Joints>& rows, int frames, int first_row,
                                       double px, double world_m, double p_right, unsigned seed,
                                       double fx = 500) {
  SyntheticHand h;
  h.K << fx, 0, 319.5, 0, fx, 239.5, 0, 0, 1;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 1);
  const Mat3 model_frame = Eigen::AngleAxisd(0.7, Vec3(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  for (int t = 0; t < frames; ++t) {
    const double s = t / h.fps;
    // Palm towards the camera, turning slowly; wrist on a smooth loop ~45 cm away.
    const Mat3 R = (Eigen::AngleAxisd(M_PI + 0.4 * std::sin(1.3 * s), Vec3::UnitX()) *
                    Eigen::AngleAxisd(0.5 * std::sin(0.9 * s), Vec3::UnitY()) *
                    Eigen::AngleAxisd(0.3 * std::cos(0.7 * s), Vec3::UnitZ()))
                       .toRotationMatrix();
    const Vec3 centre(0.06 * std::sin(1.1 * s), 0.04 * std::cos(0.8 * s), 0.45 + 0.05 * std::sin(0.6 * s));
    // The CSV's bones vary a little from row to row (they were detected);
    // a real hand's do not: its joint directions, the first row's lengths.
    const hands::Joints& row = rows.at(static_cast<size_t>(first_row + t) % rows.size());
    const hands::Joints& first = rows.at(static_cast<size_t>(first_row) % rows.size());
    hands::Joints local;
    local[0] = row[0];
    for (int j = 1; j < hands::kJoints; ++j) {
      const int p = hands::kParent[j];
      local[j] = local[p] + (row[j] - row[p]).normalized() * (first[j] - first[p]).norm();
    }
    hands::Joints cam;
    Vec3 centroid = Vec3::Zero();
    for (int j = 0; j < hands::kJoints; ++j) {
      cam[j] = R * local[j] + centre;
      centroid += local[j] / hands::kJoints;
    }
    hands::HandObservation o;
    o.score = 0.95;
    o.p_right = p_right;
    for (int j = 0; j < hands::kJoints; ++j) {
      const Vec3 p = h.K * cam[j];
      o.uv[j] = Eigen::Vector2d(p.x() / p.z() + px * noise(rng), p.y() / p.z() + px * noise(rng));
      o.confidence[j] = o.score;
      o.world[j] = model_frame * (local[j] - centroid) +
                   world_m * Vec3(noise(rng), noise(rng), noise(rng));
    }
    h.truth.push_back(cam);
    h.seen.push_back(o);
  }
  return h;
}

// Mean joint error (metres) over the frames of `fit` that `use` allows.
template <typename Use>
double Mpjpe(const hands::FittedTrack& fit, const std::vector<hands::Joints>& truth, bool pnp, Use use) {
  double sum = 0;
  int n = 0;
  for (size_t f = 0; f < fit.joints.size(); ++f) {
    if (!use(f)) continue;
    const hands::Joints& x = pnp ? fit.pnp_joints[f] : fit.joints[f];
    for (int j = 0; j < hands::kJoints; ++j) sum += (x[j] - truth[fit.first_frame + f][j]).norm();
    n += hands::kJoints;
  }
  return n ? sum / n : 0.0;
}

}  // namespace doasido::testing
