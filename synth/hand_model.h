// The project's own articulated human hand: 21 joints in OpenPose-21 order
// (wrist 0; thumb 1-4 = CMC, MCP, IP, tip; index 5-8, middle 9-12, ring
// 13-16, pinky 17-20 = MCP, PIP, DIP, tip) with adult proportions, posed from
// joint angles, and a closed surface made of capsules that follows the pose.
//
// Hand-local frame of a right hand: origin at the wrist, +y distal (towards
// the middle fingertip), +z palmar (out of the palm), +x = y x z radial
// (towards the thumb side of the palm). A left hand is the mirror image
// (x -> -x in its local frame), so `HandPose::wrist` has the same meaning
// for both sides: columns of its rotation are (d x n, d, n) with d the
// distal direction and n the palm normal in the parent frame.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "core/geometry.h"
#include "core/mesh.h"

namespace doasido::synth {

enum class Side { kLeft = 0, kRight = 1 };

using HandJoints = Eigen::Matrix<double, 21, 3, Eigen::RowMajor>;

// Joint angles in radians. Finger f: 0 thumb, 1 index, 2 middle, 3 ring,
// 4 pinky. For fingers 1-4, flex = (MCP, PIP, DIP) and abduct is MCP
// abduction (positive spreads towards the pinky side). For the thumb,
// flex = (CMC, MCP, IP) and abduct is CMC abduction (positive away from the
// palm plane). Positive flexion curls towards the palm.
struct HandPose {
  Pose wrist;  // hand-local -> parent (world or camera) frame
  std::array<std::array<double, 3>, 5> flex{};
  std::array<double, 5> abduct{};
};

// Bone lengths and capsule radii in metres (adult, ~18.5 cm wrist to middle
// fingertip at scale 1).
struct HandShape {
  double scale = 1.0;
  // Finger bases (MCP; CMC for the thumb) in the right-hand local frame.
  std::array<Vec3, 5> base = {Vec3(0.022, 0.030, 0.010), Vec3(0.026, 0.088, 0.0),
                              Vec3(0.006, 0.093, 0.0), Vec3(-0.013, 0.088, 0.0),
                              Vec3(-0.030, 0.078, 0.0)};
  std::array<std::array<double, 3>, 5> length = {{{0.042, 0.033, 0.028},
                                                  {0.042, 0.025, 0.021},
                                                  {0.047, 0.029, 0.022},
                                                  {0.044, 0.028, 0.022},
                                                  {0.034, 0.020, 0.019}}};
  std::array<double, 5> radius = {0.0110, 0.0095, 0.0097, 0.0092, 0.0082};
  double palm_radius = 0.0125;
  double wrist_radius = 0.022;
  double forearm_length = 0.06;
};

// Joint positions in the parent frame of `pose.wrist`.
HandJoints HandJointPositions(const HandPose& pose, Side side, const HandShape& shape = {});

// Capsules (segment a-b, radius r) that make up the surface, for a posed hand.
struct Capsule {
  Vec3 a, b;
  double radius = 0;
};
std::vector<Capsule> HandCapsules(const HandJoints& joints, const HandPose& pose, Side side,
                                  const HandShape& shape = {});

// The surface mesh of the capsules: each capsule a closed, outward-oriented
// triangle mesh; the vertex and face count are the same for every pose, so
// meshes of one hand over time can be stacked (T,V,3). `capsule_of_face`
// (optional) receives the capsule index of every face.
TriMesh CapsulesMesh(const std::vector<Capsule>& capsules,
                     std::vector<int>* capsule_of_face = nullptr);

// Convenience: joints and mesh of a posed hand.
struct PosedHand {
  HandJoints joints;
  std::vector<Capsule> capsules;
  TriMesh mesh;
  std::vector<int> capsule_of_face;
};
PosedHand PoseHand(const HandPose& pose, Side side, const HandShape& shape = {});

// An open, relaxed hand (slight natural flexion).
HandPose RelaxedPose(const Pose& wrist);

// Sets finger `f` to a curl c in [0, 1] (0 = relaxed, 1 = fist), keeping
// abduction; the thumb curls towards opposition.
void SetFingerCurl(HandPose& pose, int finger, double curl);

// The hand-local -> parent rotation with distal direction `d` and palm normal
// `n` (both unit, orthogonal).
Mat3 HandFrame(const Vec3& distal, const Vec3& palm_normal);

}  // namespace doasido::synth
