// A left hand from a right one, and back (`doasido hand mirror`): the hand's
// MJCF and its description reflected through a plane, so that one robot
// hand serves both sides of a bimanual clip.
//
// The reflection S flips one axis (y by default, the plane the built-in
// sharpa_left was drawn from) of every frame in the kinematic tree, which
// leaves the model a proper rigid-body model:
//  - positions (pos, fromto, anchor, a light's dir): S v;
//  - orientations: the rotation R becomes S R S, a rotation again; a
//    quaternion (w, v) becomes (w, -S v), an axisangle (a, t) becomes
//    (-S a, t), xyaxes (x, y) the columns of S R S; euler angles and zaxis
//    are turned into the quaternion they mean (the compiler's angle unit and
//    eulerseq; the shortest rotation onto zaxis) and mirrored as one. A
//    geom's frame given by fromto spins freely about its axis: the compiler
//    picks the spin, which does not matter for the capsules and cylinders
//    fromto makes;
//  - a hinge's axis a becomes -S a, so that a joint angle means the same
//    motion on both sides (flexion stays positive, ranges and actuator
//    control ranges stay as they are); a slide's axis becomes S a;
//  - full inertia matrices become S I S;
//  - meshes are reflected by their scale (MuJoCo reverses the faces of a
//    mesh scaled by a negative factor, as the menagerie's left hands do):
//    the flipped component of every mesh scale, written or inherited,
//    changes sign.
// Names, sizes, joint ranges, actuators, tendons and equality constraints
// are left as they are. A joint's type is read from the element that
// carries its axis (hinge when it does not say), so a slide joint whose
// type comes from a default class but whose axis is its own is mirrored as
// a hinge: write the type beside the axis.
//
// The description's points keep their bodies and sites; their offsets are
// reflected; its side swaps. Mirroring twice gives the original model back.
#pragma once

#include <filesystem>
#include <string>

#include "robot/embodiment.h"

namespace doasido::retarget {

struct MirrorOptions {
  char axis = 'y';   // the flipped axis: 'x', 'y' or 'z'
  // The mirrored hand's name (and file stem); "" swaps "right" and "left"
  // in the original name, or appends "_mirrored" when it has neither.
  std::string name;
};

// `xml` (one self-contained document, such as PrepareMjcf's) reflected.
// `label` names the document in errors. Throws Error("bad_mjcf") for
// malformed XML or numbers, Error("bad_config") for an axis other than x,
// y, z.
std::string MirrorMjcf(const std::string& xml, char axis, const std::string& label);

// The description reflected: points' offsets, side swapped, renamed to
// `name`, its model file `model`.
Embodiment MirrorEmbodiment(const Embodiment& hand, char axis, const std::string& name,
                            const std::string& model);

// The name MirrorOptions::name = "" gives `name`.
std::string MirroredName(const std::string& name);

struct MirroredHand {
  Embodiment embodiment;          // as written, model_path resolved
  std::filesystem::path description;  // <out_dir>/<name>.json
  std::filesystem::path model;        // <out_dir>/<name>.xml
};

// Mirrors `hand`'s prepared model (PrepareMjcf: includes inlined, absolute
// asset paths) and description into `out_dir` (created). Throws as
// MirrorMjcf, and Error("io") naming a file that cannot be written.
MirroredHand MirrorHand(const Embodiment& hand, const std::filesystem::path& out_dir,
                        const MirrorOptions& options = {});

}  // namespace doasido::retarget
