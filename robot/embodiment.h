// Embodiments: which robot hand, and how its bodies and sites correspond to
// the 21 OpenPose hand keypoints (REFERENCE.md section 3: wrist 0, thumb
// 1-4, index 5-8, middle 9-12, ring 13-16, pinky 17-20; 4, 8, 12, 16, 20 are
// the fingertips). A small JSON description makes any MJCF hand usable:
//
//   {"name": "allegro_right", "side": "right", "model": "wonik_allegro/right_hand.xml",
//    "floating_base": true, "scale": 0,
//    "points": [{"keypoint": 0, "body": "palm", "pos": [0, 0, -0.095]},
//               {"keypoint": 8, "body": "ff_tip", "pos": [0, 0, 0.035], "fingertip": true},
//               {"keypoint": 5, "body": "ff_proximal", "weight": 0.3}, ...]}
//
// "model" is looked up relative to the description's folder, then the
// robots folder given to the loader, then the built-in models folder
// (robot/models). Each point names a body or a site and an offset in its
// frame. "scale" > 0 fixes the human-to-robot scale; 0 adapts it per
// sequence (kinematic_retarget.h).
//
// BuildHandModel adds the 6-DoF floating wrist the retargeting solves for:
// a mount body with slide x, y, z then hinge x, y, z joints (world axes,
// rotation Rx*Ry*Rz), holding a fixed frame that turns the hand into the
// canonical wrist frame of the human keypoints (fingers +z, palm +x, thumb
// side +y for a right hand). That frame is found automatically by aligning
// the robot's wrist and knuckle points at qpos0 to a canonical human palm,
// so zero wrist angles mean "hand as in the keypoint data's canonical frame"
// and the Euler singularity (|ry| = pi/2) stays far from typical motion.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/geometry.h"
#include "robot/mj_model.h"
#include "robot/mjcf_compat.h"

namespace doasido::retarget {

struct EmbodimentPoint {
  int keypoint = -1;             // OpenPose-21 index
  std::string body;              // exactly one of body and site
  std::string site;
  std::array<double, 3> pos{0, 0, 0};  // offset in the body's or site's frame, metres
  double weight = 1.0;
  bool fingertip = false;        // counted in fingertip error metrics
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(EmbodimentPoint, keypoint, body, site, pos, weight,
                                                fingertip)

struct Embodiment {
  std::string name;
  std::string side = "right";  // "right" or "left"
  std::string model;           // model file as written in the description
  bool floating_base = true;
  double scale = 0;            // human->robot scale; 0 = adapt per sequence
  std::vector<EmbodimentPoint> points;
  std::filesystem::path model_path;  // resolved absolute path (not serialised)
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Embodiment, name, side, model, floating_base, scale,
                                                points)

// The folder holding doasido's own hand models and their descriptions (the
// build copies robot/models there): $DOASIDO_MODELS_DIR, else
// share/doasido/models beside the executable's folder (core/data_dirs.h).
std::filesystem::path BuiltinModelsDir();
// The folder of third-party robot models and descriptions: $DOASIDO_ROBOTS_DIR,
// else share/doasido/robots beside the executable's folder (the build links
// it to ../shared/data/robots when that exists), when it exists; else "".
std::string DefaultRobotsDir();

// Reads and checks a description (keypoints in 0..20, each point naming one
// body or site, at least one fingertip, model file found). Throws
// Error("bad_embodiment") naming the file and field.
Embodiment LoadEmbodiment(const std::filesystem::path& json_path,
                          const std::filesystem::path& robots_dir = {});

// `name_or_path` is a .json path, or a name looked up as <name>.json in
// `robots_dir` and then BuiltinModelsDir(). Aliases: "shadow" ->
// shadow_right, "allegro" -> allegro_right, "sharpa" -> sharpa_right.
Embodiment FindEmbodiment(const std::string& name_or_path,
                          const std::filesystem::path& robots_dir);

// One description point resolved against a compiled model.
struct ModelPoint {
  int body = -1;  // body id, or -1 when a site
  int site = -1;  // site id, or -1 when a body
  Vec3 offset = Vec3::Zero();
  double weight = 1.0;
  int keypoint = -1;
  bool fingertip = false;
};

// The body BuildHandModel adds for the floating wrist (a bimanual scene has
// one per hand, its name prefixed; see bimanual_retarget.h).
inline constexpr const char* kWristMountBody = "doasido_wrist_mount";
// Its joints: slides x, y, z, then hinges x, y, z (world axes).
inline constexpr const char* kWristJoints[6] = {"doasido_wrist_x",  "doasido_wrist_y",  "doasido_wrist_z",
                                                "doasido_wrist_rx", "doasido_wrist_ry", "doasido_wrist_rz"};

struct HandModel {
  Embodiment embodiment;
  std::string xml;  // the prepared MJCF with the floating wrist, self-contained
  std::vector<CompatChange> changes;
  ModelPtr model;
  std::vector<int> wrist_qpos;  // qpos addresses of x y z rx ry rz (empty without floating base)
  std::vector<int> finger_qpos; // qpos addresses of every other 1-DoF joint
  std::vector<ModelPoint> points;
  Mat3 mount = Mat3::Identity();  // fixed rotation between wrist joints and hand
};

// Prepares the hand's MJCF (mjcf_compat), adds the floating wrist with
// position actuators, appends `scene_xml` (a <mujoco> document whose
// children, e.g. a floor and an object, are merged in; relative paths in it
// are relative to `scene_dir`), and compiles. Throws Error("bad_mjcf") or
// Error("bad_embodiment") when a named body or site is missing.
HandModel BuildHandModel(const Embodiment& embodiment, const std::string& scene_xml = {},
                         const std::filesystem::path& scene_dir = {});

// Why a body named in a description can be missing from `mjcf_xml`'s
// model, as a clause to append to the refusal: <compiler fusestatic="true">
// (set in the model, or MuJoCo's URDF default when the model was converted
// from URDF) merges joint-less bodies such as palms and fingertip links into
// their parents; the clause names the option to change.
std::string MissingBodyHint(const std::string& mjcf_xml);

// World position of a model point for the kinematics in `d`.
Vec3 PointPosition(const mjModel* m, const mjData* d, const ModelPoint& point);

// Names of the model's joints in qpos order (one per 1-DoF joint; free and
// ball joints are not expected in a hand).
std::vector<std::string> QposNames(const mjModel* m);

}  // namespace doasido::retarget
