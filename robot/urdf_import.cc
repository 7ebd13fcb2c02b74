#include "robot/urdf_import.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <set>

#include <mujoco/mujoco.h>
#include <spdlog/spdlog.h>
#include <tinyxml2.h>

#include "core/config_check.h"
#include "core/error.h"
#include "core/file_text.h"
#include "core/mesh.h"
#include "robot/mj_model.h"
#include "robot/mjcf_compat.h"

namespace doasido::retarget {
namespace {

namespace fs = std::filesystem;
using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;

std::string Str(const char* s) { return s ? s : ""; }

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string Fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

std::string Rerun(const fs::path& urdf) { return "then rerun `" + UrdfImportCommand(urdf) + "`"; }

void LoadUrdf(const fs::path& urdf, XMLDocument& doc) {
  const std::string text =
      ReadFileOrThrow(urdf, kBadUrdfError, "cannot read the URDF file; check the path");
  if (doc.Parse(text.c_str()) != tinyxml2::XML_SUCCESS) {
    throw Error(kBadUrdfError, std::string("malformed XML (") + doc.ErrorStr() + "); fix it, " +
                Rerun(urdf), {.file = urdf.string()});
  }
  const XMLElement* root = doc.RootElement();
  const std::string name = root ? root->Name() : "";
  if (name == "robot") return;
  if (name == "mujoco") {
    throw Error(kWrongRootError,
                "root element is <mujoco>: this is an MJCF model, not a URDF; describe it with `" +
                    MjcfImportCommand(urdf) + "`",
                {.file = urdf.string(), .field = "<mujoco>"});
  }
  throw Error(kWrongRootError,
              "root element is <" + name + ">, a URDF's is <robot>; export the hand as URDF "
              "(for xacro: `xacro hand.urdf.xacro > hand.urdf`), " + Rerun(urdf),
              {.file = urdf.string(), .field = "<" + name + ">"});
}

// Every moving joint must be limited: the retargeter clamps to the limits
// and position actuators take their control range from them.
void CheckJoints(const fs::path& urdf, const XMLElement* robot) {
  for (const XMLElement* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const std::string name = Str(j->Attribute("name")), type = Str(j->Attribute("type"));
    const std::string field = "joint name=" + name;
    // MuJoCo 2.2.2's URDF reader crashes on a type it does not know (found
    // by hand_import_fuzz), and on a joint without both links.
    static const std::set<std::string> kTypes = {"revolute", "continuous", "prismatic",
                                                 "fixed",    "floating",   "planar"};
    if (!kTypes.count(type)) {
      throw Error(kBadUrdfError,
                  "joint '" + name + "' has type '" + type + "'; URDF's joint types are revolute, "
                  "continuous, prismatic, fixed, floating and planar, " + Rerun(urdf),
                  {.file = urdf.string(), .field = field});
    }
    for (const char* end : {"parent", "child"}) {
      const XMLElement* link = j->FirstChildElement(end);
      if (!link || !link->Attribute("link")) {
        throw Error(kBadUrdfError,
                    "joint '" + name + "' has no <" + end + " link=\"..\"/>, " + Rerun(urdf),
                    {.file = urdf.string(), .field = field});
      }
    }
    if (type == "fixed") continue;
    if (type == "continuous" || type == "floating" || type == "planar") {
      throw Error(kUnlimitedJointError,
                  "joint '" + name + "' is " + type + ", without limits; a finger joint needs them: "
                  "make it type=\"revolute\" (or \"prismatic\") with <limit lower=\"..\" upper=\"..\" "
                  "effort=\"..\" velocity=\"..\"/>, or \"fixed\", " + Rerun(urdf),
                  {.file = urdf.string(), .field = field});
    }
    const XMLElement* limit = j->FirstChildElement("limit");
    const bool has = limit && limit->Attribute("lower") && limit->Attribute("upper");
    if (!has || !(limit->DoubleAttribute("upper") > limit->DoubleAttribute("lower"))) {
      throw Error(kUnlimitedJointError,
                  "joint '" + name + "' (" + type + ") has no <limit lower upper> with lower < upper; "
                  "add <limit lower=\"..\" upper=\"..\" effort=\"..\" velocity=\"..\"/> with the "
                  "joint's range in radians (metres for prismatic), " + Rerun(urdf),
                  {.file = urdf.string(), .field = field});
    }
  }
}

// MuJoCo 2.2.2's URDF reader drops <mimic>: the coupled joint becomes
// independent, which the retargeter then moves freely.
std::vector<std::string> MimicWarnings(const XMLElement* robot) {
  std::vector<std::string> out;
  for (const XMLElement* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const XMLElement* mimic = j->FirstChildElement("mimic");
    if (!mimic) continue;
    out.push_back("joint '" + Str(j->Attribute("name")) + "' mimics '" + Str(mimic->Attribute("joint")) +
                  "' in the URDF; MuJoCo 2.2.2 drops <mimic>, so it moves independently in the MJCF "
                  "(couple it with an <equality><joint joint1=.. joint2=.. polycoef=..> if it must)");
    spdlog::warn("hand import: {}", out.back());
  }
  return out;
}

// Where `filename` of a <mesh> points: package:// and file:// prefixes
// resolved against the URDF's folder and up to three of its parents.
std::vector<fs::path> MeshCandidates(const fs::path& urdf_dir, std::string filename) {
  std::vector<fs::path> out;
  if (filename.rfind("file://", 0) == 0) filename = filename.substr(7);
  if (filename.rfind("package://", 0) == 0) {
    const std::string rest = filename.substr(10);
    const size_t slash = rest.find('/');
    const std::string package = rest.substr(0, slash);
    const std::string inside = slash == std::string::npos ? "" : rest.substr(slash + 1);
    fs::path dir = urdf_dir;
    for (int up = 0; up < 4; ++up) {
      out.push_back(dir / inside);
      out.push_back(dir / package / inside);
      if (!dir.has_parent_path() || dir.parent_path() == dir) break;
      dir = dir.parent_path();
    }
    return out;
  }
  const fs::path p(filename);
  out.push_back(p.is_absolute() ? p : urdf_dir / p);
  return out;
}

// Copies or converts every mesh into `mesh_dir` and points the URDF at the copy.
std::vector<std::string> GatherMeshes(const fs::path& urdf, XMLElement* robot, const fs::path& mesh_dir) {
  std::vector<std::string> log;
  std::set<std::string> used;
  std::map<std::string, std::string> done;  // source -> new name
  const fs::path dir = fs::absolute(urdf).parent_path();
  for (XMLElement* link = robot->FirstChildElement("link"); link; link = link->NextSiblingElement("link")) {
    for (const char* part : {"visual", "collision"}) {
      for (XMLElement* v = link->FirstChildElement(part); v; v = v->NextSiblingElement(part)) {
        XMLElement* geometry = v->FirstChildElement("geometry");
        XMLElement* mesh = geometry ? geometry->FirstChildElement("mesh") : nullptr;
        if (!mesh) continue;
        const std::string filename = Str(mesh->Attribute("filename"));
        const std::string field = "link name=" + Str(link->Attribute("name")) + "/" + part +
                                  "/mesh filename=" + filename;
        fs::path found;
        std::string looked;
        for (const fs::path& c : MeshCandidates(dir, filename)) {
          looked += (looked.empty() ? "" : ", ") + c.lexically_normal().string();
          if (found.empty() && fs::is_regular_file(c)) found = c;
        }
        if (found.empty()) {
          throw Error(kMissingMeshError,
                      "mesh '" + filename + "' not found (looked for " + looked + "); put the file "
                      "there or correct filename= in the URDF, " + Rerun(urdf),
                      {.file = urdf.string(), .field = field});
        }
        const std::string key = fs::canonical(found).string();
        if (!done.count(key)) {
          const std::string ext = Lower(found.extension().string());
          const bool native = ext == ".obj" || ext == ".stl";
          std::string stem = found.stem().string(), out = stem + (native ? ext : ".obj");
          for (int k = 1; used.count(out); ++k) out = stem + "_" + std::to_string(k) + (native ? ext : ".obj");
          used.insert(out);
          if (native) {
            fs::copy_file(found, mesh_dir / out, fs::copy_options::overwrite_existing);
            log.push_back("copied " + found.string() + " -> meshes/" + out);
          } else {
            try {
              SaveObj(LoadMesh(found), mesh_dir / out);
            } catch (const Error& e) {
              throw Error(e.code(), e.message() + "; MuJoCo 2.2.2 reads OBJ and STL: convert the "
                          "mesh to one of them, " + Rerun(urdf), {.file = found.string(), .field = field});
            }
            log.push_back("converted " + found.string() + " -> meshes/" + out + " (assimp)");
          }
          done[key] = out;
        }
        mesh->SetAttribute("filename", done[key].c_str());
      }
    }
  }
  return log;
}

// MuJoCo's URDF options: mesh folder, no fusing, visuals kept.
void SetCompiler(XMLDocument& doc, XMLElement* robot) {
  while (XMLElement* old = robot->FirstChildElement("mujoco")) robot->DeleteChild(old);
  XMLElement* mujoco = doc.NewElement("mujoco");
  XMLElement* compiler = mujoco->InsertNewChildElement("compiler");
  compiler->SetAttribute("meshdir", "meshes");
  compiler->SetAttribute("strippath", "false");
  compiler->SetAttribute("fusestatic", "false");
  compiler->SetAttribute("discardvisual", "false");
  compiler->SetAttribute("balanceinertia", "true");
  robot->InsertFirstChild(mujoco);
}

void SaveDoc(const XMLDocument& doc, const fs::path& path) {
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  std::ofstream out(path);
  out << printer.CStr();
  if (!out) throw Error("io", "cannot write file", {.file = path.string()});
}

// Loads the prepared URDF and saves it as MJCF at `mjcf`.
void ConvertWithMujoco(const fs::path& urdf, const fs::path& prepared, const fs::path& mjcf) {
  char error[1000] = "";
  mjModel* m = mj_loadXML(prepared.c_str(), nullptr, error, sizeof(error));
  if (!m) {
    throw Error(kBadUrdfError, std::string("MuJoCo 2.2.2 refused the URDF: ") + error +
                "; fix the element it names (links that move need an <inertial> with positive "
                "mass, or collision geometry), " + Rerun(urdf), {.file = urdf.string()});
  }
  ModelPtr model(m);
  if (!mj_saveLastXML(mjcf.c_str(), m, error, sizeof(error))) {
    throw Error("io", std::string("MuJoCo could not save the MJCF: ") + error, {.file = mjcf.string()});
  }
}

// Adds a position actuator per limited hinge or slide joint (gains from
// PositionGain) and critical joint damping 2 sqrt(kp M0).
void AddActuators(const fs::path& mjcf, const std::string& name, double hold_deflection) {
  const PreparedMjcf prepared = PrepareMjcf(mjcf);
  ModelPtr model = CompileMjcfText(prepared.xml, mjcf.string());
  const mjModel* m = model.get();
  DataPtr data = MakeData(m);
  mj_forward(m, data.get());
  XMLDocument doc;
  doc.Parse(TryReadFile(mjcf).value_or("").c_str());
  XMLElement* root = doc.RootElement();
  root->SetAttribute("model", name.c_str());
  std::map<std::string, XMLElement*> joints;
  std::vector<XMLElement*> stack = {root};
  while (!stack.empty()) {
    XMLElement* e = stack.back();
    stack.pop_back();
    if (std::string(e->Name()) == "joint" && e->Attribute("name")) joints[e->Attribute("name")] = e;
    for (XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) stack.push_back(c);
  }
  XMLElement* act = root->FirstChildElement("actuator");
  if (!act) act = root->InsertNewChildElement("actuator");
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE) continue;
    const std::string jname = Str(mj_id2name(m, mjOBJ_JOINT, j));
    if (!m->jnt_limited[j] || !joints.count(jname)) continue;
    const int b = m->jnt_bodyid[j];
    const double lo = m->jnt_range[2 * j], hi = m->jnt_range[2 * j + 1];
    const Eigen::Map<const Vec3> com(data->subtree_com + 3 * b), anchor(data->xanchor + 3 * j);
    const double kp = PositionGain(m->body_subtreemass[b], (com - anchor).norm(), hi - lo, hold_deflection);
    const double damping = 2 * std::sqrt(kp * m->dof_M0[m->jnt_dofadr[j]]);
    joints[jname]->SetAttribute("damping", Fmt(damping).c_str());
    XMLElement* a = act->InsertNewChildElement("position");
    a->SetAttribute("name", jname.c_str());
    a->SetAttribute("joint", jname.c_str());
    a->SetAttribute("kp", Fmt(kp).c_str());
    a->SetAttribute("ctrllimited", "true");
    a->SetAttribute("ctrlrange", (Fmt(lo) + " " + Fmt(hi)).c_str());
  }
  SaveDoc(doc, mjcf);
}

std::string SafeName(const std::string& s) {
  std::string out;
  for (char c : s) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' ? c : '_';
  return out.empty() ? "hand" : out;
}

ImportedHand Describe(const fs::path& mjcf, const fs::path& out_dir, const std::string& name,
                      const std::string& side, const std::string& model_field, const std::string& comment) {
  ImportedHand out;
  out.mjcf = mjcf;
  ModelPtr model = CompileMjcfText(PrepareMjcf(mjcf).xml, mjcf.string());
  out.structure = AnalyzeHand(model.get(), mjcf.string());
  out.described = DescribeHand(model.get(), out.structure, name, side, model_field);
  out.description = out_dir / (name + ".json");
  WriteEmbodimentJson(out.described, comment, out.description);
  return out;
}

}  // namespace

void CheckConfig(const HandImportOptions& o, const std::string& section) {
  if (o.side != "right" && o.side != "left") {
    throw Error("bad_config", "side must be right or left, not '" + o.side + "'", {.field = section + ".side"});
  }
  RequireInRange(section, "hold_deflection", o.hold_deflection, 1e-6, 1.0);
}

double PositionGain(double subtree_mass, double lever, double range, double hold_deflection) {
  const double g = 9.81;
  return subtree_mass * g * std::max(lever, 0.01) / (hold_deflection * std::max(range, 1e-3));
}

ImportedHand ImportUrdf(const fs::path& urdf, const fs::path& out_dir, const HandImportOptions& options) {
  CheckConfig(options, "hand_import");
  XMLDocument doc;
  LoadUrdf(urdf, doc);
  XMLElement* robot = doc.RootElement();
  CheckJoints(urdf, robot);
  const std::string name = SafeName(options.name.empty() ? urdf.stem().string() : options.name);
  fs::create_directories(out_dir / "meshes");
  const std::vector<std::string> meshes = GatherMeshes(urdf, robot, out_dir / "meshes");
  SetCompiler(doc, robot);
  const fs::path prepared = out_dir / (name + ".urdf");
  SaveDoc(doc, prepared);
  const fs::path mjcf = out_dir / (name + ".xml");
  ConvertWithMujoco(urdf, prepared, mjcf);
  AddActuators(mjcf, name, options.hold_deflection);
  ImportedHand out = Describe(mjcf, out_dir, name, options.side, mjcf.filename().string(),
                              "Generated by `doasido hand import` from " + fs::absolute(urdf).string() +
                                  ". Edit bodies, offsets (pos, metres, in the body's frame) and weights "
                                  "freely, then run `doasido hand check` on this file.");
  out.meshes = meshes;
  out.warnings = MimicWarnings(robot);
  return out;
}

ImportedHand DescribeMjcf(const fs::path& mjcf, const fs::path& out_dir, const HandImportOptions& options) {
  CheckConfig(options, "hand_import");
  const std::string name = SafeName(options.name.empty() ? mjcf.stem().string() : options.name);
  fs::create_directories(out_dir);
  const fs::path abs = fs::absolute(mjcf).lexically_normal();
  return Describe(abs, out_dir, name, options.side, abs.string(),
                  "Generated by `doasido hand import --mjcf` from " + abs.string() +
                      ". Edit bodies, offsets (pos, metres, in the body's frame) and weights freely, "
                      "then run `doasido hand check` on this file.");
}

std::string UrdfImportCommand(const fs::path& urdf) {
  return "doasido hand import --urdf " + urdf.string() + " --out " +
         (urdf.parent_path() / (urdf.stem().string() + "_hand")).string();
}

std::string MjcfImportCommand(const fs::path& mjcf) {
  return "doasido hand import --mjcf " + mjcf.string() + " --out " +
         (mjcf.parent_path() / (mjcf.stem().string() + "_hand")).string();
}

fs::path ImportedDescriptionPath(const fs::path& model) {
  return model.parent_path() / (model.stem().string() + "_hand") / (SafeName(model.stem().string()) + ".json");
}

}  // namespace doasido::retarget
