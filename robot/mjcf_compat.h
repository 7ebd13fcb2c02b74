// Makes community MJCF load in MuJoCo 2.2.2 (the version Debian ships).
//
// Newer models (menagerie after 2023, MuJoCo >= 3) use attributes that 2.2.2
// rejects. PrepareMjcf reads a model, inlines its <include> files, makes
// asset paths absolute (so the text can be compiled from anywhere) and
// rewrites what 2.2.2 does not know, reporting every rewrite (returned and
// logged with spdlog::warn):
//
//   option integrator="implicitfast"  -> "implicit" (same damping treatment,
//                                       plus Coriolis terms; slower, stabler)
//   range/ctrlrange/forcerange without limited/ctrllimited/forcelimited
//                                     -> the flag set to "true" (MuJoCo >= 3
//                                       infers it; 2.2.2 with autolimits off
//                                       refuses the model)
//   position inheritrange="r"         -> ctrlrange = joint range shrunk by r
//                                       about its middle, from a first compile
//   position dampratio="z" / kv="k"   -> added to the JOINT's damping:
//                                       k = 2 z sqrt(kp * M0), M0 the joint's
//                                       diagonal inertia at qpos0 (what MuJoCo
//                                       3 uses). Why joint damping and not a
//                                       <general> actuator with a velocity
//                                       bias: joint damping is integrated
//                                       implicitly by both the Euler and the
//                                       implicit integrator of 2.2, so stiff
//                                       fingers stay stable at the seed's 5 ms
//                                       step; the one difference is that it is
//                                       not clipped by the actuator forcerange.
//                                       Only joint transmissions are converted;
//                                       others are dropped with a warning.
//   joint actuatorfrcrange/actuatorfrclimited, body gravcomp,
//   mesh maxhullvert                  -> removed (no 2.2 equivalent)
//
// Elements 2.2.2 cannot express (<replicate>, <frame>, <flexcomp>) and PLY
// meshes raise Error("bad_mjcf") naming the file and element.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/config.h"

namespace doasido::retarget {

struct CompatChange {
  std::string file;       // the MJCF file the attribute was in
  std::string element;    // e.g. "position name=ffa0" or "default class=x/position"
  std::string attribute;  // the attribute rewritten
  std::string old_value;
  std::string new_value;  // "" when removed
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(CompatChange, file, element, attribute, old_value,
                                                new_value)

struct PreparedMjcf {
  std::string xml;  // one self-contained document, absolute asset paths
  std::vector<CompatChange> changes;
};

// Reads `path` (and its includes) and applies the rewrites above. Throws
// Error("bad_mjcf") naming the file for unreadable or malformed XML, missing
// includes, and constructs 2.2.2 cannot express.
PreparedMjcf PrepareMjcf(const std::filesystem::path& path);

// Same for XML text; relative include and asset paths are taken relative to
// `base_dir`, and `label` stands for the file name in changes and errors.
PreparedMjcf PrepareMjcfText(const std::string& xml, const std::filesystem::path& base_dir,
                             const std::string& label);

}  // namespace doasido::retarget
