// Generating a hand's embodiment description (embodiment.h) from its
// kinematic tree, so that a new hand needs no hand-written JSON.
//
// Read at qpos0 (fingers as modelled, usually straight):
//   palm      the lowest common ancestor of every body subtree that holds a
//             hinge joint (wrist joints above it, e.g. Shadow's, are left out);
//   chains    one per child subtree of the palm that holds a hinge; its
//             distal body is the leaf with the most hinges above it (ties:
//             the farthest from the palm), which is the fingertip body;
//   flexion   the chain's hinges parallel (within 35 degrees) to its most
//             distal hinge, which always flexes; the first is the knuckle;
//   thumb     with three or more chains, the chain whose flexion axis is the
//             least parallel to the others' (the opposing finger); with two,
//             the chain whose knuckle sits nearest the palm's origin;
//   fingers   the other chains ordered across the palm along their flexion
//             axis starting from the thumb's side: index, middle, ring, pinky;
//   tip point the far end of the distal body's geometry along the finger;
//   wrist     the palm's origin when it lies in the proximal 40% of the palm
//             (palm frames placed at the wrist: Shadow, Sharpa), else the end
//             of the palm's geometry opposite the fingers (Allegro), on the
//             line through the knuckles' centroid.
// The OpenPose-21 keypoints map as the hand-written descriptions do: wrist 0
// (weight 1), fingertips 4 8 12 16 20, knuckles 5 9 13 17 (0.5), the next
// flexion joints 6 7, 10 11, ... (0.1), thumb IP 3 (0.2) and MCP 2 (0.3).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "core/geometry.h"
#include "robot/embodiment.h"

namespace doasido::retarget {

inline constexpr const char* kFingerNames[5] = {"thumb", "index", "middle", "ring", "pinky"};

struct HandChain {
  std::string finger;        // one of kFingerNames, or "extra" (a fifth non-thumb chain)
  std::vector<int> bodies;   // body ids, palm's child first, distal body last
  std::vector<int> joints;   // hinge joint ids along the chain, proximal first
  std::vector<int> flexion;  // the subset of `joints` that flex the finger
  int tip_body = -1;
  Vec3 tip_offset = Vec3::Zero();  // fingertip point in tip_body's frame
};

struct HandStructure {
  int palm = -1;                    // body id
  Vec3 wrist_offset = Vec3::Zero(); // wrist point in the palm's frame
  std::vector<HandChain> chains;    // thumb first, then index, middle, ring, pinky, extras
  std::vector<std::string> notes;   // how the thumb and the order were decided
};

// Analyses the hand in `m` (a hand model without the floating wrist, or with
// it: the wrist bodies are above the palm). Throws Error("bad_hand") naming
// `label` when fewer than two chains carry hinge joints.
HandStructure AnalyzeHand(const mjModel* m, const std::string& label);

struct HandDescription {
  Embodiment embodiment;
  std::vector<std::string> notes;  // one per point: what it is and where it came from
};

// The description of `m`: points on bodies (joint anchors, the tip and wrist
// points above), named `name`, model file `model` as it will be written.
HandDescription DescribeHand(const mjModel* m, const HandStructure& s, const std::string& name,
                             const std::string& side, const std::string& model);

// Writes the description as the hand-written ones are laid out (name, side,
// model, floating_base, scale, points), each point with its "note", plus a
// top-level "comment" (LoadEmbodiment ignores both). Throws Error("io").
void WriteEmbodimentJson(const HandDescription& d, const std::string& comment,
                         const std::filesystem::path& path);

// The body a description point lies on (its own body, or its site's body), or -1.
int PointBody(const mjModel* m, const EmbodimentPoint& p);

}  // namespace doasido::retarget
