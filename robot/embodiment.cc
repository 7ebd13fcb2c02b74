#include "robot/embodiment.h"

#include <cctype>
#include <cmath>
#include <map>

#include <Eigen/SVD>
#include <spdlog/spdlog.h>
#include <tinyxml2.h>

#include "core/data_dirs.h"
#include "core/error.h"
#include "core/file_text.h"
#include "core/json_input.h"
#include "robot/mjcf_text.h"
#include "robot/urdf_import.h"

namespace doasido::retarget {
namespace {

using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;
using tinyxml2::XMLNode;

// A typical right hand's wrist and knuckles (OpenPose 0, 5, 9, 13, 17) in the
// canonical wrist frame: medians of the 621 frames of the dex-retargeting
// sample in ../shared/data/retarget (wrist-centred, fingers +z, palm +x).
const std::map<int, Vec3> kCanonicalPalm = {{0, {0.0, 0.0, 0.0}},
                                            {5, {0.0, 0.0264, 0.0958}},
                                            {9, {0.0, 0.0, 0.0966}},
                                            {13, {0.0091, -0.0205, 0.0906}},
                                            {17, {0.017, -0.0355, 0.0747}}};

std::string Fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

// Moves every top-level body under a mount body carrying the six wrist joints
// and a fixed frame with rotation `mount`; adds a position actuator per joint.
struct BaseGains {
  double kp[6] = {2000, 2000, 2000, 20, 20, 20};
  double damping[6] = {80, 80, 80, 1, 1, 1};
};

// Gains for a stiff, critically damped wrist: natural frequency 40 rad/s
// (omega * dt = 0.2 at the seed's 5 ms step), so gravity sags the base by
// g / omega^2 = 6 mm whatever the hand weighs. `inertia` holds the mount
// joints' diagonal inertia at qpos0 (mass for the slides).
BaseGains GainsFor(const double inertia[6]) {
  BaseGains g;
  const double omega = 40.0;
  for (int i = 0; i < 6; ++i) {
    g.kp[i] = inertia[i] * omega * omega;
    g.damping[i] = 2.0 * inertia[i] * omega;
  }
  return g;
}

std::string AddFloatingBase(const std::string& xml, const Mat3& mount, const BaseGains& gains,
                            const std::string& label) {
  XMLDocument doc;
  ParseMjcfText(xml, label, doc);
  XMLElement* root = doc.RootElement();
  XMLElement* world = root->FirstChildElement("worldbody");
  if (!world) throw Error("bad_mjcf", "model has no <worldbody>", {.file = label});
  XMLElement* base = doc.NewElement("body");
  base->SetAttribute("name", kWristMountBody);
  XMLElement* inertial = base->InsertNewChildElement("inertial");
  inertial->SetAttribute("pos", "0 0 0");
  inertial->SetAttribute("mass", "0.01");
  inertial->SetAttribute("diaginertia", "1e-6 1e-6 1e-6");
  const char* axes[3] = {"1 0 0", "0 1 0", "0 0 1"};
  for (int i = 0; i < 6; ++i) {
    XMLElement* j = base->InsertNewChildElement("joint");
    j->SetAttribute("name", kWristJoints[i]);
    j->SetAttribute("type", i < 3 ? "slide" : "hinge");
    j->SetAttribute("axis", axes[i % 3]);
    j->SetAttribute("pos", "0 0 0");
    j->SetAttribute("limited", "false");
    j->SetAttribute("damping", Fmt(gains.damping[i]).c_str());
    j->SetAttribute("armature", i < 3 ? "0" : "0.005");
    j->SetAttribute("frictionloss", "0");
    j->SetAttribute("stiffness", "0");
    j->SetAttribute("ref", "0");
  }
  XMLElement* frame = base->InsertNewChildElement("body");
  frame->SetAttribute("name", "doasido_hand_frame");
  const Quat q(mount);
  frame->SetAttribute("quat", (Fmt(q.w()) + " " + Fmt(q.x()) + " " + Fmt(q.y()) + " " +
                               Fmt(q.z())).c_str());
  std::vector<XMLElement*> bodies;
  for (XMLElement* b = world->FirstChildElement("body"); b; b = b->NextSiblingElement("body")) {
    bodies.push_back(b);
  }
  if (bodies.empty()) throw Error("bad_mjcf", "no body under <worldbody>", {.file = label});
  for (XMLElement* b : bodies) frame->InsertEndChild(b);  // moves the node
  world->InsertEndChild(base);
  XMLElement* act = root->InsertNewChildElement("actuator");
  for (int i = 0; i < 6; ++i) {
    XMLElement* a = act->InsertNewChildElement("position");
    a->SetAttribute("name", kWristJoints[i]);
    a->SetAttribute("joint", kWristJoints[i]);
    a->SetAttribute("kp", Fmt(gains.kp[i]).c_str());
    a->SetAttribute("ctrllimited", "true");
    a->SetAttribute("ctrlrange", i < 3 ? "-3 3" : "-6.3 6.3");
    a->SetAttribute("forcelimited", "false");
  }
  return PrintMjcf(doc);
}

// Appends the children of `scene`'s root to `xml`'s root.
std::string Merge(const std::string& xml, const std::string& scene, const std::string& label) {
  XMLDocument doc;
  ParseMjcfText(xml, label, doc);
  AppendRootChildren(doc, scene, "scene");
  return PrintMjcf(doc);
}

std::vector<ModelPoint> ResolvePoints(const mjModel* m, const Embodiment& e,
                                      const std::string& hint = {}) {
  std::vector<ModelPoint> out;
  for (size_t i = 0; i < e.points.size(); ++i) {
    const EmbodimentPoint& p = e.points[i];
    ModelPoint mp;
    mp.offset = Vec3(p.pos[0], p.pos[1], p.pos[2]);
    mp.weight = p.weight;
    mp.keypoint = p.keypoint;
    mp.fingertip = p.fingertip;
    if (!p.site.empty()) {
      mp.site = NameToId(m, mjOBJ_SITE, p.site);
      if (mp.site < 0) {
        throw Error("bad_embodiment", "model has no site '" + p.site + "'",
                    {.file = e.model_path.string(), .field = "points[" + std::to_string(i) + "]"});
      }
    } else {
      mp.body = NameToId(m, mjOBJ_BODY, p.body);
      if (mp.body < 0) {
        throw Error("bad_embodiment", "model has no body '" + p.body + "'" + hint +
                    "; or name an existing body in the description (`doasido hand check` lists "
                    "the model's chains)",
                    {.file = e.model_path.string(), .field = "points[" + std::to_string(i) + "]"});
      }
    }
    out.push_back(mp);
  }
  return out;
}

// The mount rotation taking the robot's palm points at qpos0 onto the
// canonical human palm; identity when fewer than three palm points map.
Mat3 CanonicalMount(const mjModel* m, const Embodiment& e, const std::string& hint) {
  DataPtr d = MakeData(m);
  mj_kinematics(m, d.get());
  const std::vector<ModelPoint> points = ResolvePoints(m, e, hint);
  std::vector<Vec3> robot, human;
  for (const ModelPoint& p : points) {
    auto it = kCanonicalPalm.find(p.keypoint);
    if (it == kCanonicalPalm.end()) continue;
    robot.push_back(PointPosition(m, d.get(), p));
    Vec3 h = it->second;
    if (e.side == "left") h.y() = -h.y();
    human.push_back(h);
  }
  if (robot.size() < 3) return Mat3::Identity();
  return FitRigid(robot, human).R();
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// A robot model (URDF or MJCF) where a hand description is expected: the
// refusal says which command makes the description.
[[noreturn]] void RefuseRobotModel(const std::filesystem::path& model, ErrorSite site) {
  const bool urdf = Lower(model.extension().string()) == ".urdf";
  const std::string command = urdf ? UrdfImportCommand(model) : MjcfImportCommand(model);
  std::string message = "'" + model.string() + "' is " + (urdf ? "a URDF" : "an MJCF") +
                        " robot model, not a hand description; run `" + command + "` once";
  message += site.field == "model"
                 ? " and use the description it writes, " + ImportedDescriptionPath(model).string() +
                       " (or point \"model\" at the .xml it writes)"
                 : " and use the description it writes: --hand " + ImportedDescriptionPath(model).string();
  if (site.file.empty()) site.file = model.string();
  throw Error("bad_embodiment", message, site);
}

std::filesystem::path FindModelFile(const std::string& model, const std::filesystem::path& desc_dir,
                                    const std::filesystem::path& robots_dir) {
  const std::filesystem::path p(model);
  if (p.is_absolute()) return p;
  for (const auto& dir : {desc_dir, robots_dir, BuiltinModelsDir()}) {
    if (dir.empty()) continue;
    if (std::filesystem::exists(dir / p)) return std::filesystem::absolute(dir / p);
  }
  return {};
}

}  // namespace

std::filesystem::path BuiltinModelsDir() { return DataDir("models", "DOASIDO_MODELS_DIR"); }

std::string DefaultRobotsDir() {
  const std::filesystem::path p = DataDir("robots", "DOASIDO_ROBOTS_DIR");
  return std::filesystem::exists(p) ? std::filesystem::weakly_canonical(p).string() : std::string();
}

std::string MissingBodyHint(const std::string& xml) {
  XMLDocument doc;
  if (doc.Parse(xml.c_str()) == tinyxml2::XML_SUCCESS && doc.RootElement()) {
    for (const XMLElement* c = doc.RootElement()->FirstChildElement("compiler"); c;
         c = c->NextSiblingElement("compiler")) {
      if (c->Attribute("fusestatic") && std::string(c->Attribute("fusestatic")) == "true") {
        return "; the model's <compiler fusestatic=\"true\"> merges bodies without joints (palms, "
               "fingertip links) into their parents: set fusestatic=\"false\" in its <compiler>";
      }
    }
  }
  return "; if the model was converted from URDF with MuJoCo's default <compiler "
         "fusestatic=\"true\">, bodies without joints (palms, fingertip links) were merged into "
         "their parents: convert it again with fusestatic=\"false\" (`doasido hand import --urdf` does)";
}


namespace {

// A keypoint written as a float past int's range would make the conversion
// to int undefined behaviour (found by hand_import_fuzz).
void RequireWholeKeypoints(const Json& json, const std::string& file) {
  if (!json.is_object() || !json.contains("points") || !json.at("points").is_array()) return;
  const Json& points = json.at("points");
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].is_object() || !points[i].contains("keypoint")) continue;
    const Json& k = points[i].at("keypoint");
    if (k.is_number_float() || (k.is_number() && (k.get<double>() < 0 || k.get<double>() > 20))) {
      throw Error("bad_embodiment", "keypoint must be an OpenPose-21 index 0..20, got " + k.dump(),
                  {.file = file, .field = "points[" + std::to_string(i) + "].keypoint"});
    }
  }
}

}  // namespace

Embodiment LoadEmbodiment(const std::filesystem::path& json_path,
                          const std::filesystem::path& robots_dir) {
  const std::string file = json_path.string();
  const std::string text =
      ReadFileOrThrow(json_path, "bad_embodiment", "cannot read embodiment description");
  Embodiment e;
  try {
    const Json json = ParseJsonInput(text, {.file = file}, {.max_depth = 16, .max_bytes = 16u << 20});
    RequireWholeKeypoints(json, file);
    e = json.get<Embodiment>();
  } catch (const Error& ex) {
    if (ex.code() == "bad_embodiment") throw;  // already names the file and field
    throw Error("bad_embodiment", ex.code() + ": " + ex.message(), {.file = file});
  } catch (const nlohmann::json::exception& ex) {
    throw Error("bad_embodiment", std::string("invalid JSON: ") + ex.what(), {.file = file});
  }
  if (e.name.empty()) e.name = json_path.stem().string();
  if (e.side != "right" && e.side != "left") {
    throw Error("bad_embodiment", "side must be \"right\" or \"left\"", {.file = file, .field = "side"});
  }
  int tips = 0;
  for (size_t i = 0; i < e.points.size(); ++i) {
    const EmbodimentPoint& p = e.points[i];
    const std::string field = "points[" + std::to_string(i) + "]";
    if (p.keypoint < 0 || p.keypoint > 20) {
      throw Error("bad_embodiment", "keypoint must be an OpenPose-21 index 0..20",
                  {.file = file, .field = field + ".keypoint"});
    }
    if (p.body.empty() == p.site.empty()) {
      throw Error("bad_embodiment", "give exactly one of body and site", {.file = file, .field = field});
    }
    if (!(p.weight > 0)) {
      throw Error("bad_embodiment", "weight must be positive", {.file = file, .field = field + ".weight"});
    }
    tips += p.fingertip;
  }
  if (tips == 0) throw Error("bad_embodiment", "no fingertip point", {.file = file, .field = "points"});
  e.model_path = FindModelFile(e.model, json_path.parent_path(), robots_dir);
  if (Lower(std::filesystem::path(e.model).extension().string()) == ".urdf") {
    RefuseRobotModel(e.model_path.empty() ? std::filesystem::path(e.model) : e.model_path,
                     {.file = file, .field = "model"});
  }
  if (e.model_path.empty()) {
    throw Error("bad_embodiment", "model file '" + e.model + "' not found beside the description, in "
                "the robots folder or in the built-in models", {.file = file, .field = "model"});
  }
  return e;
}

Embodiment FindEmbodiment(const std::string& name_or_path, const std::filesystem::path& robots_dir) {
  const std::string ext = Lower(std::filesystem::path(name_or_path).extension().string());
  if (ext == ".json") return LoadEmbodiment(name_or_path, robots_dir);
  if (ext == ".urdf" || ext == ".xml") RefuseRobotModel(name_or_path, {.field = "hand"});
  std::string name = name_or_path;
  if (name == "shadow" || name == "allegro" || name == "sharpa") name += "_right";
  for (const auto& dir : {robots_dir, BuiltinModelsDir()}) {
    if (!dir.empty() && std::filesystem::exists(dir / (name + ".json"))) {
      return LoadEmbodiment(dir / (name + ".json"), robots_dir);
    }
  }
  throw Error("bad_embodiment", "unknown hand '" + name_or_path + "': give a built-in name (sharpa_right, "
              "sharpa_left, shadow, allegro), a description .json, or import a robot model first with "
              "`doasido hand import --urdf HAND.urdf --out DIR` (or --mjcf HAND.xml) and pass "
              "DIR/HAND.json", {.field = "hand"});
}

HandModel BuildHandModel(const Embodiment& embodiment, const std::string& scene_xml,
                         const std::filesystem::path& scene_dir) {
  HandModel hand;
  hand.embodiment = embodiment;
  PreparedMjcf prepared = PrepareMjcf(embodiment.model_path);
  hand.changes = prepared.changes;
  const std::string label = embodiment.model_path.string();
  std::string xml = prepared.xml;
  if (embodiment.floating_base) {
    ModelPtr probe = CompileMjcfText(AddFloatingBase(xml, Mat3::Identity(), {}, label), label);
    hand.mount = CanonicalMount(probe.get(), embodiment, MissingBodyHint(xml));
    double inertia[6];
    for (int i = 0; i < 6; ++i) {
      const int j = NameToId(probe.get(), mjOBJ_JOINT, kWristJoints[i]);
      inertia[i] = probe->dof_M0[probe->jnt_dofadr[j]];
    }
    xml = AddFloatingBase(xml, hand.mount, GainsFor(inertia), label);
  }
  if (!scene_xml.empty()) {
    PreparedMjcf scene = PrepareMjcfText(scene_xml, scene_dir, (scene_dir / "scene").string());
    xml = Merge(xml, scene.xml, label);
  }
  hand.xml = xml;
  hand.model = CompileMjcfText(xml, label);
  const mjModel* m = hand.model.get();
  hand.points = ResolvePoints(m, embodiment, MissingBodyHint(xml));
  for (int j = 0; j < m->njnt; ++j) {
    const int type = m->jnt_type[j];
    if (type != mjJNT_HINGE && type != mjJNT_SLIDE) continue;
    const char* name = mj_id2name(m, mjOBJ_JOINT, j);
    const std::string n = name ? name : "";
    bool wrist = false;
    for (int i = 0; i < 6; ++i) wrist |= n == kWristJoints[i];
    if (!wrist) hand.finger_qpos.push_back(m->jnt_qposadr[j]);
  }
  if (embodiment.floating_base) {
    for (const char* name : kWristJoints) {
      hand.wrist_qpos.push_back(m->jnt_qposadr[NameToId(m, mjOBJ_JOINT, name)]);
    }
  }
  return hand;
}

Vec3 PointPosition(const mjModel* m, const mjData* d, const ModelPoint& point) {
  (void)m;
  const mjtNum* pos = point.site >= 0 ? d->site_xpos + 3 * point.site : d->xpos + 3 * point.body;
  const mjtNum* mat = point.site >= 0 ? d->site_xmat + 9 * point.site : d->xmat + 9 * point.body;
  Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> r(mat);
  return Eigen::Map<const Vec3>(pos) + r * point.offset;
}

std::vector<std::string> QposNames(const mjModel* m) {
  std::vector<std::string> names(m->nq);
  for (int j = 0; j < m->njnt; ++j) {
    const char* name = mj_id2name(m, mjOBJ_JOINT, j);
    const int adr = m->jnt_qposadr[j];
    const int width = m->jnt_type[j] == mjJNT_FREE ? 7 : m->jnt_type[j] == mjJNT_BALL ? 4 : 1;
    for (int k = 0; k < width; ++k) {
      names[adr + k] = (name ? std::string(name) : "joint" + std::to_string(j)) +
                       (width > 1 ? "_" + std::to_string(k) : "");
    }
  }
  return names;
}

}  // namespace doasido::retarget
