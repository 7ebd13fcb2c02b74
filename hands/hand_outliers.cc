#include "hands/hand_outliers.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace doasido::hands {
namespace {

using Points = Eigen::Matrix<double, 3, Eigen::Dynamic>;

// The rotation R minimising |R a - b| over centred point sets (Kabsch).
Mat3 BestRotation(const Points& a, const Points& b) {
  const Eigen::Matrix3d H = b * a.transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

Points Centred(const std::array<Eigen::Vector3d, kJoints>& joints) {
  Points p(3, kJoints);
  for (int j = 0; j < kJoints; ++j) p.col(j) = joints[j];
  return p.colwise() - p.rowwise().mean();
}

// RMS distance of `b` from `a` after the best rotation.
double ShapeDistance(const Points& a, const Points& b) {
  return std::sqrt((BestRotation(a, b) * a - b).squaredNorm() / kJoints);
}

Points Mirrored(Points p) {
  p.row(2) *= -1;
  return p;
}

}  // namespace

std::vector<bool> MirroredFrames(const Track& track) {
  std::vector<Points> kept;  // the shapes as the track's handedness, in frame order
  std::vector<size_t> observed;
  std::vector<bool> mirrored;
  for (size_t f = 0; f < track.frames.size(); ++f) {
    if (!track.frames[f]) continue;
    const Points shape = Centred(track.frames[f]->world);
    int mirror_votes = 0, votes = 0;
    for (size_t k = kept.size(); k-- > 0 && votes < kHandednessVotes; ++votes) {
      if (ShapeDistance(kept[k], Mirrored(shape)) < ShapeDistance(kept[k], shape)) ++mirror_votes;
    }
    mirrored.push_back(2 * mirror_votes > votes);
    kept.push_back(mirrored.back() ? Mirrored(shape) : shape);
    observed.push_back(f);
  }
  const auto count = std::count(mirrored.begin(), mirrored.end(), true);
  const bool invert = 2 * count > static_cast<long>(mirrored.size());
  std::vector<bool> out(track.frames.size(), false);
  for (size_t k = 0; k < observed.size(); ++k) out[observed[k]] = mirrored[k] != invert;
  return out;
}

double HandTurnDeg(const Joints& a, const Joints& b) {
  constexpr int kPalm[] = {0, 1, 5, 9, 13, 17};
  Points A(3, 6), B(3, 6);
  for (int k = 0; k < 6; ++k) {
    A.col(k) = a[kPalm[k]];
    B.col(k) = b[kPalm[k]];
  }
  const Mat3 R = BestRotation(A.colwise() - A.rowwise().mean(), B.colwise() - B.rowwise().mean());
  return Eigen::AngleAxisd(R).angle() * 180 / M_PI;
}

std::vector<bool> UntrustedFrames(const std::vector<Joints>& joints, double max_move_m,
                                  double max_turn_deg, int max_run) {
  // Pieces as [start, end) between cuts.
  std::vector<std::pair<size_t, size_t>> pieces;
  size_t start = 0;
  for (size_t f = 1; f <= joints.size(); ++f) {
    const bool cut = f == joints.size() || (joints[f][0] - joints[f - 1][0]).norm() > max_move_m ||
                     HandTurnDeg(joints[f - 1], joints[f]) > max_turn_deg;
    if (!cut) continue;
    pieces.emplace_back(start, f);
    start = f;
  }
  std::vector<bool> untrusted(joints.size(), false);
  if (pieces.size() < 2) return untrusted;
  const auto longest = std::max_element(pieces.begin(), pieces.end(), [](auto a, auto b) {
    return a.second - a.first < b.second - b.first;
  });
  for (auto it = pieces.begin(); it != pieces.end(); ++it) {
    if (it == longest || it->second - it->first > static_cast<size_t>(max_run)) continue;
    for (size_t f = it->first; f < it->second; ++f) untrusted[f] = true;
  }
  return untrusted;
}

Track WithoutFrames(const Track& track, const std::vector<bool>& drop) {
  Track out = track;
  out.untrusted.resize(out.frames.size(), false);
  for (size_t f = 0; f < out.frames.size(); ++f) {
    if (!drop[f] || !out.frames[f]) continue;
    out.frames[f].reset();
    out.untrusted[f] = true;
  }
  size_t first = 0, end = out.frames.size();
  while (first < end && !out.frames[first]) ++first;
  while (end > first && !out.frames[end - 1]) --end;
  out.first_frame += static_cast<int>(first);
  out.frames = {out.frames.begin() + first, out.frames.begin() + end};
  out.untrusted = {out.untrusted.begin() + first, out.untrusted.begin() + end};
  return out;
}

}  // namespace doasido::hands
