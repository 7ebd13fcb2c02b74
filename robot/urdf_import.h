// Bringing a new hand in: a URDF becomes an MJCF model the retargeter uses
// plus a generated, editable description (hand_description.h); an MJCF hand
// gets the description only.
//
// URDF import, through MuJoCo 2.2.2's own URDF reader:
//  1. checks the URDF first, so that refusals name the file, the element and
//     the next step: root element <robot>; every revolute/prismatic joint
//     with <limit lower upper>, no continuous or floating joints; every
//     <mesh filename> found (package:// and file:// resolved against the
//     URDF's folder and its parents);
//  2. copies OBJ and STL meshes into <out>/meshes (MuJoCo 2.2.2 reads them)
//     and converts others (PLY, DAE, GLB, ...) to OBJ through assimp;
//  3. writes <out>/<name>.urdf with <mujoco><compiler meshdir="meshes"
//     fusestatic="false" discardvisual="false" .../></mujoco>: MuJoCo's URDF
//     default fusestatic="true" merges joint-less links (palms, fingertip
//     links) into their parents and the description's bodies go missing;
//  4. loads it with mj_loadXML, saves it with mj_saveLastXML and adds one
//     position actuator per joint (see PositionGains) and the matching joint
//     damping, giving <out>/<name>.xml;
//  5. writes <out>/<name>.json, the generated description (floating_base
//     true: BuildHandModel adds the 6-DoF wrist when the hand is used).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "robot/embodiment.h"
#include "robot/hand_description.h"

namespace doasido::retarget {

// Error codes of the import (Error::code()).
inline constexpr const char* kWrongRootError = "wrong_root";          // not a <robot> document
inline constexpr const char* kMissingMeshError = "missing_mesh";      // mesh file not found
inline constexpr const char* kUnlimitedJointError = "unlimited_joint"; // joint without limits
inline constexpr const char* kBadUrdfError = "bad_urdf";              // malformed, or MuJoCo refused it

struct HandImportOptions {
  std::string side = "right";    // "right" or "left"
  std::string name;              // file stem and description name; "" = the input file's stem
  double hold_deflection = 0.05; // PositionGains: fraction of the range that holds the finger
};

// Throws Error("bad_config") for a side other than right/left or a
// hold_deflection outside (0, 1].
void CheckConfig(const HandImportOptions& o, const std::string& section);

struct ImportedHand {
  std::filesystem::path mjcf;         // the model the description points at
  std::filesystem::path description;  // <out>/<name>.json
  HandDescription described;
  HandStructure structure;
  std::vector<std::string> meshes;    // what happened to each mesh ("copied a.obj", "converted b.ply")
  std::vector<std::string> warnings;  // what the MJCF does not keep (e.g. <mimic> couplings)
};

// Imports `urdf` into `out_dir` (created) as described above. Throws Error
// with the codes above, or bad_mesh (a mesh assimp cannot read), naming the
// URDF file and the element, and saying what to change and what to rerun.
ImportedHand ImportUrdf(const std::filesystem::path& urdf, const std::filesystem::path& out_dir,
                        const HandImportOptions& options = {});

// Describes an MJCF hand: <out>/<name>.json whose "model" is the absolute
// path of `mjcf` (the model is not copied). Throws Error("bad_mjcf") or
// Error("bad_hand").
ImportedHand DescribeMjcf(const std::filesystem::path& mjcf, const std::filesystem::path& out_dir,
                          const HandImportOptions& options = {});

// Position gain of a finger joint: holds the joint's subtree (mass M, centre
// of mass at distance L from the axis at qpos0) against gravity within
// `hold_deflection` of the joint's range R: kp = M g L / (hold_deflection R).
// Lever arms below 1 cm count as 1 cm.
double PositionGain(double subtree_mass, double lever, double range, double hold_deflection);

// The commands that make a URDF or MJCF hand usable, quoted in refusals:
//   doasido hand import --urdf F --out <F's folder>/<stem>_hand
std::string UrdfImportCommand(const std::filesystem::path& urdf);
std::string MjcfImportCommand(const std::filesystem::path& mjcf);
// The description path those commands write (<out>/<stem>.json).
std::filesystem::path ImportedDescriptionPath(const std::filesystem::path& model);

}  // namespace doasido::retarget
