#include "robot/mjcf_compat.h"

#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <spdlog/spdlog.h>
#include <tinyxml2.h>

#include "core/error.h"
#include "core/file_text.h"
#include "robot/mj_model.h"
#include "robot/urdf_import.h"

namespace doasido::retarget {
namespace {

using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;
using tinyxml2::XMLNode;

// Marks elements whose rewrite needs a compiled model, with the file they
// came from (includes are inlined before that pass). Removed before output.
constexpr const char* kSourceAttr = "doasido_source_file";

const std::set<std::string> kActuators = {"general",  "motor",    "position", "velocity",
                                          "intvelocity", "damper", "cylinder", "muscle",
                                          "adhesion"};

std::string Str(const char* s) { return s ? std::string(s) : std::string(); }

bool IsUnder(const XMLElement* e, const char* parent_name) {
  const XMLNode* p = e->Parent();
  return p && p->ToElement() && std::string(p->ToElement()->Name()) == parent_name;
}

std::string Describe(const XMLElement* e) {
  std::string s = e->Name();
  if (e->Attribute("name")) {
    s += " name=" + Str(e->Attribute("name"));
  } else if (e->Attribute("class")) {
    s += " class=" + Str(e->Attribute("class"));
  }
  if (IsUnder(e, "default")) {
    const XMLElement* p = e->Parent()->ToElement();
    s = "default class=" + (p->Attribute("class") ? Str(p->Attribute("class")) : "main") + "/" + s;
  }
  return s;
}

void Record(std::vector<CompatChange>& changes, CompatChange change) {
  spdlog::warn("mjcf_compat: {}: <{}> {}=\"{}\" -> {}", change.file, change.element,
               change.attribute, change.old_value,
               change.new_value.empty() ? "removed" : "\"" + change.new_value + "\"");
  changes.push_back(std::move(change));
}

void ParseFile(const std::filesystem::path& path, const std::string& label, XMLDocument& doc) {
  const std::string text = ReadFileOrThrow(path, "bad_mjcf", "cannot read MJCF file", label);
  if (doc.Parse(text.c_str()) != tinyxml2::XML_SUCCESS) {
    throw Error("bad_mjcf", std::string("malformed XML: ") + Str(doc.ErrorStr()), {.file = label});
  }
}

void Remove(XMLElement* e, const char* attr, const std::string& file,
            std::vector<CompatChange>& changes) {
  if (const char* v = e->Attribute(attr)) {
    Record(changes, {file, Describe(e), attr, v, ""});
    e->DeleteAttribute(attr);
  }
}

// Rewrites that need nothing but the element itself.
void StaticPass(XMLElement* e, const std::string& file, std::vector<CompatChange>& changes) {
  const std::string name = e->Name();
  if (name == "replicate" || name == "frame" || name == "flexcomp" || name == "flex") {
    throw Error("bad_mjcf", "<" + name + "> needs MuJoCo >= 3 and has no 2.2 rewrite",
                {.file = file, .field = name});
  }
  if (name == "option" && Str(e->Attribute("integrator")) == "implicitfast") {
    e->SetAttribute("integrator", "implicit");
    Record(changes, {file, Describe(e), "integrator", "implicitfast", "implicit"});
  }
  const bool ranged = name == "joint" || ((name == "spatial" || name == "fixed") && IsUnder(e, "tendon"));
  if ((ranged && e->Attribute("range") && !e->Attribute("limited")) ||
      (kActuators.count(name) && ((e->Attribute("ctrlrange") && !e->Attribute("ctrllimited")) ||
                                  (e->Attribute("forcerange") && !e->Attribute("forcelimited"))))) {
    e->SetAttribute(kSourceAttr, file.c_str());  // decided in LimitedPass, which sees defaults
  }
  if (name == "joint") {
    Remove(e, "actuatorfrcrange", file, changes);
    Remove(e, "actuatorfrclimited", file, changes);
  }
  if (kActuators.count(name)) {
    if (e->Attribute("dampratio") || e->Attribute("inheritrange") ||
        (name == "position" && e->Attribute("kv"))) {
      e->SetAttribute(kSourceAttr, file.c_str());
    }
  }
  if (name == "body") Remove(e, "gravcomp", file, changes);
  if (name == "mesh") {
    Remove(e, "maxhullvert", file, changes);
    std::string f = Str(e->Attribute("file"));
    for (auto& c : f) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (f.size() > 4 && f.substr(f.size() - 4) == ".ply") {
      throw Error("bad_mjcf", "MuJoCo 2.2.2 cannot read PLY meshes; convert to STL or OBJ",
                  {.file = file, .field = "mesh file=" + Str(e->Attribute("file"))});
    }
  }
  for (XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
    StaticPass(c, file, changes);
  }
}

// Replaces every <include file=F> below `e` with the children of F's root.
// MuJoCo resolves include paths against the main model's folder.
void InlineIncludes(XMLElement* e, XMLDocument& doc, const std::filesystem::path& base_dir,
                    std::vector<CompatChange>& changes, int depth) {
  if (depth > 16) throw Error("bad_mjcf", "include nesting too deep or cyclic");
  XMLElement* c = e->FirstChildElement();
  while (c) {
    XMLElement* next = c->NextSiblingElement();
    if (std::string(c->Name()) == "include") {
      const std::string rel = Str(c->Attribute("file"));
      const std::filesystem::path path = base_dir / rel;
      XMLDocument sub;
      ParseFile(path, path.string(), sub);
      XMLElement* root = sub.RootElement();
      if (!root || std::string(root->Name()) != "mujoco") {
        throw Error("bad_mjcf", "included file has no <mujoco> root", {.file = path.string()});
      }
      StaticPass(root, path.string(), changes);
      InlineIncludes(root, sub, base_dir, changes, depth + 1);
      XMLNode* after = c;
      for (const XMLNode* n = root->FirstChild(); n; n = n->NextSibling()) {
        if (n->ToComment()) continue;
        XMLNode* clone = n->DeepClone(&doc);
        e->InsertAfterChild(after, clone);
        after = clone;
      }
      e->DeleteChild(c);
    } else {
      InlineIncludes(c, doc, base_dir, changes, depth);
    }
    c = next;
  }
}

void ForEachElement(XMLElement* e, const std::function<void(XMLElement*)>& f) {
  f(e);
  for (XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) ForEachElement(c, f);
}

void AbsolutizeAssets(XMLElement* root, const std::filesystem::path& base_dir) {
  std::string meshdir, texturedir, assetdir;
  ForEachElement(root, [&](XMLElement* e) {
    if (std::string(e->Name()) != "compiler") return;
    if (e->Attribute("meshdir")) meshdir = e->Attribute("meshdir");
    if (e->Attribute("texturedir")) texturedir = e->Attribute("texturedir");
    if (e->Attribute("assetdir")) assetdir = e->Attribute("assetdir");
    e->DeleteAttribute("meshdir");
    e->DeleteAttribute("texturedir");
    e->DeleteAttribute("assetdir");
  });
  if (meshdir.empty()) meshdir = assetdir;
  if (texturedir.empty()) texturedir = assetdir;
  auto fix = [&](XMLElement* e, const char* attr, const std::string& dir) {
    const char* v = e->Attribute(attr);
    if (!v) return;
    std::filesystem::path p(v);
    if (p.is_absolute()) return;
    std::filesystem::path d(dir);
    if (!d.is_absolute()) d = base_dir / d;
    e->SetAttribute(attr, (d / p).lexically_normal().string().c_str());
  };
  ForEachElement(root, [&](XMLElement* e) {
    const std::string name = e->Name();
    if (IsUnder(e, "default")) return;
    if (name == "mesh" || name == "hfield" || name == "skin") fix(e, "file", meshdir);
    if (name == "texture") {
      for (const char* a : {"file", "fileright", "fileleft", "fileup", "filedown", "filefront",
                            "fileback"}) {
        fix(e, a, texturedir);
      }
    }
  });
}

// An attribute of an actuator, from the element or else its default class chain.
struct Resolved {
  std::string value;
  const XMLElement* where = nullptr;
};

class DefaultClasses {
 public:
  explicit DefaultClasses(XMLElement* root) {
    ForEachElement(root, [&](XMLElement* e) {
      if (std::string(e->Name()) != "default") return;
      const bool top = !IsUnder(e, "default");
      classes_[top && !e->Attribute("class") ? "main" : Str(e->Attribute("class"))] = e;
    });
  }

  std::optional<Resolved> Actuator(const XMLElement* act, const char* attr) const {
    if (const char* v = act->Attribute(attr)) return Resolved{v, act};
    const std::string cls = act->Attribute("class") ? act->Attribute("class") : "main";
    auto it = classes_.find(cls);
    const XMLElement* d = it == classes_.end() ? nullptr : it->second;
    while (d) {
      for (const XMLElement* c = d->FirstChildElement(); c; c = c->NextSiblingElement()) {
        if (kActuators.count(c->Name()) && c->Attribute(attr)) {
          return Resolved{c->Attribute(attr), c};
        }
      }
      d = IsUnder(d, "default") ? d->Parent()->ToElement() : nullptr;
    }
    return std::nullopt;
  }

 private:
  std::map<std::string, XMLElement*> classes_;
};

// True when `flag` is set on `e` or inherited from its default classes
// (class attribute, the nearest childclass, else "main").
bool FlagInherited(const XMLElement* e, const char* flag,
                   const std::map<std::string, XMLElement*>& classes) {
  if (e->Attribute(flag)) return true;
  const bool actuator = kActuators.count(e->Name()) > 0;
  auto in_default = [&](const XMLElement* d) {
    for (; d; d = IsUnder(d, "default") ? d->Parent()->ToElement() : nullptr) {
      for (const XMLElement* c = d->FirstChildElement(); c; c = c->NextSiblingElement()) {
        const bool same = actuator ? kActuators.count(c->Name()) > 0 : Str(c->Name()) == e->Name();
        if (same && c->Attribute(flag)) return true;
      }
    }
    return false;
  };
  if (IsUnder(e, "default")) {
    const XMLElement* d = e->Parent()->ToElement();
    return IsUnder(d, "default") && in_default(d->Parent()->ToElement());
  }
  std::string cls = Str(e->Attribute("class"));
  for (const XMLNode* p = e->Parent(); cls.empty() && p && p->ToElement(); p = p->Parent()) {
    if (p->ToElement()->Attribute("childclass")) cls = p->ToElement()->Attribute("childclass");
  }
  if (cls.empty()) cls = "main";
  auto it = classes.find(cls);
  return it != classes.end() && in_default(it->second);
}

// Sets limited/ctrllimited/forcelimited where a range is given and no flag
// is set or inherited: MuJoCo >= 3 infers them, 2.2.2 (autolimits off)
// refuses the model.
void LimitedPass(XMLElement* root, std::vector<CompatChange>& changes) {
  std::map<std::string, XMLElement*> classes;
  ForEachElement(root, [&](XMLElement* e) {
    if (std::string(e->Name()) != "default") return;
    const bool top = !IsUnder(e, "default");
    classes[top && !e->Attribute("class") ? "main" : Str(e->Attribute("class"))] = e;
  });
  bool autolimits = false;
  ForEachElement(root, [&](XMLElement* e) {
    if (std::string(e->Name()) == "compiler" && Str(e->Attribute("autolimits")) == "true") {
      autolimits = true;
    }
  });
  if (autolimits) return;
  ForEachElement(root, [&](XMLElement* e) {
    const char* src = e->Attribute(kSourceAttr);
    if (!src) return;
    const std::string file = src;
    for (const auto& [value, flag] : {std::pair{"range", "limited"}, {"ctrlrange", "ctrllimited"},
                                      {"forcerange", "forcelimited"}}) {
      if (!e->Attribute(value) || FlagInherited(e, flag, classes)) continue;
      e->SetAttribute(flag, "true");
      Record(changes, {file, Describe(e), flag, "", "true"});
    }
  });
}

std::string Print(const XMLDocument& doc) {
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return printer.CStr();
}

std::string FormatDouble(double v) {
  std::ostringstream ss;
  ss.precision(6);
  ss << v;
  return ss.str();
}

// The steps of ModelPass.

// A position actuator with attributes MuJoCo 2.2.2 lacks, where each was
// set (its file and, when inherited, from which default class).
struct PendingActuator {
  int id;
  XMLElement* element;
  std::optional<Resolved> dampratio, kv, inheritrange, kp;
  std::string range_file, damp_file, range_desc, damp_desc;
};

std::vector<PendingActuator> PendingActuators(XMLElement* root, const std::string& label,
                                              const std::vector<XMLElement*>& actuators) {
  DefaultClasses classes(root);
  auto source_file = [&](const XMLElement* e) {
    for (const XMLElement* x = e; x; x = x->Parent() ? x->Parent()->ToElement() : nullptr) {
      if (x->Attribute(kSourceAttr)) return Str(x->Attribute(kSourceAttr));
    }
    return label;
  };
  std::vector<PendingActuator> pending;
  for (int i = 0; i < static_cast<int>(actuators.size()); ++i) {
    XMLElement* a = actuators[i];
    if (std::string(a->Name()) != "position") continue;
    PendingActuator p{i, a, classes.Actuator(a, "dampratio"), classes.Actuator(a, "kv"),
                      classes.Actuator(a, "inheritrange"), classes.Actuator(a, "kp")};
    if (p.inheritrange) {
      p.range_file = source_file(p.inheritrange->where);
      if (p.inheritrange->where != a) p.range_desc = " (from " + Describe(p.inheritrange->where) + ")";
    }
    for (const auto* r : {&p.kv, &p.dampratio}) {
      if (!*r) continue;
      p.damp_file = source_file((*r)->where);
      if ((*r)->where != a) p.damp_desc = " (from " + Describe((*r)->where) + ")";
    }
    if (p.dampratio || p.kv || p.inheritrange) pending.push_back(p);
  }
  return pending;
}

// inheritrange as the ctrlrange it means on the actuator's limited joint
// `j` (dropped, with a warning, when there is none).
void ConvertInheritRange(const mjModel& m, const PendingActuator& p, bool joint_trn, int j,
                         const std::string& desc, std::vector<CompatChange>& changes) {
  const std::string& file = p.range_file;
  const std::string& where_for = p.range_desc;
  if (!joint_trn || !m.jnt_limited[j]) {
    Record(changes, {file, desc + where_for, "inheritrange", p.inheritrange->value, ""});
    spdlog::warn("mjcf_compat: {} inheritrange dropped: needs a limited joint", desc);
    return;
  }
  const double r = std::stod(p.inheritrange->value);
  const double lo = m.jnt_range[2 * j], hi = m.jnt_range[2 * j + 1];
  const double mid = 0.5 * (lo + hi), half = 0.5 * r * (hi - lo);
  const std::string range = FormatDouble(mid - half) + " " + FormatDouble(mid + half);
  p.element->SetAttribute("ctrlrange", range.c_str());
  p.element->SetAttribute("ctrllimited", "true");
  Record(changes, {file, desc + where_for, "inheritrange", p.inheritrange->value,
                   "ctrlrange=" + range});
}

// dampratio or kv as damping added to the actuator's joint `j`
// (`extra_damping`); dropped when the actuator drives no joint.
void ConvertDamping(const mjModel& m, const PendingActuator& p, bool joint_trn, int j,
                    const std::string& desc, std::vector<CompatChange>& changes,
                    std::map<int, double>& extra_damping) {
  const std::optional<Resolved>& damp = p.dampratio ? p.dampratio : p.kv;
  const char* attr = p.dampratio ? "dampratio" : "kv";
  const std::string& file = p.damp_file;
  const double value = std::stod(damp->value);
  if (!joint_trn) {
    Record(changes, {file, desc + p.damp_desc, attr, damp->value, ""});
    return;
  }
  const double kp = p.kp ? std::stod(p.kp->value) : 1.0;
  const int dof = m.jnt_dofadr[j];
  const double kv = p.dampratio ? 2.0 * value * std::sqrt(kp * m.dof_M0[dof]) : value;
  extra_damping[j] += kv;
  const char* jname = mj_id2name(&m, mjOBJ_JOINT, j);
  Record(changes, {file, desc + p.damp_desc, attr, damp->value,
                   "joint " + Str(jname) + " damping += " + FormatDouble(kv)});
}

// Writes each joint's damping plus what its actuators added.
void AddJointDamping(const mjModel& m, const std::vector<XMLElement*>& joints,
                     const std::map<int, double>& extra_damping) {
  for (const auto& [j, extra] : extra_damping) {
    const char* jname = mj_id2name(&m, mjOBJ_JOINT, j);
    XMLElement* je = nullptr;
    for (XMLElement* e : joints) {
      if (jname && Str(e->Attribute("name")) == jname) je = e;
    }
    if (!je) {
      spdlog::warn("mjcf_compat: joint {} has no name; damping not converted", j);
      continue;
    }
    const double total = m.dof_damping[m.jnt_dofadr[j]] + extra;
    je->SetAttribute("damping", FormatDouble(total).c_str());
  }
}

// Rewrites that need the compiled model: inheritrange and dampratio/kv.
void ModelPass(XMLDocument& doc, const std::string& label, std::vector<CompatChange>& changes) {
  XMLElement* root = doc.RootElement();
  std::vector<XMLElement*> actuators;
  std::vector<XMLElement*> joints;
  ForEachElement(root, [&](XMLElement* e) {
    if (IsUnder(e, "actuator")) actuators.push_back(e);
    if (std::string(e->Name()) == "joint" && e->Attribute("name") && !IsUnder(e, "default")) {
      joints.push_back(e);
    }
  });
  const std::vector<PendingActuator> pending = PendingActuators(root, label, actuators);
  ForEachElement(root, [&](XMLElement* e) {
    for (const char* a : {"dampratio", "inheritrange", kSourceAttr}) e->DeleteAttribute(a);
    if (std::string(e->Name()) == "position") e->DeleteAttribute("kv");
  });
  if (pending.empty()) return;
  ModelPtr m = CompileMjcfText(Print(doc), label);
  std::map<int, double> extra_damping;  // joint id -> added damping
  for (const PendingActuator& p : pending) {
    const std::string desc = Describe(p.element);
    if (p.id >= m->nu) continue;
    const bool joint_trn = m->actuator_trntype[p.id] == mjTRN_JOINT ||
                           m->actuator_trntype[p.id] == mjTRN_JOINTINPARENT;
    const int j = m->actuator_trnid[2 * p.id];
    if (p.inheritrange) ConvertInheritRange(*m, p, joint_trn, j, desc, changes);
    if (p.dampratio || p.kv) ConvertDamping(*m, p, joint_trn, j, desc, changes, extra_damping);
  }
  AddJointDamping(*m, joints, extra_damping);
}

void StripMarks(XMLElement* root) {
  ForEachElement(root, [](XMLElement* e) { e->DeleteAttribute(kSourceAttr); });
}

}  // namespace

PreparedMjcf PrepareMjcfText(const std::string& xml, const std::filesystem::path& base_dir,
                             const std::string& label) {
  XMLDocument doc;
  if (doc.Parse(xml.c_str()) != tinyxml2::XML_SUCCESS) {
    throw Error("bad_mjcf", std::string("malformed XML: ") + Str(doc.ErrorStr()), {.file = label});
  }
  XMLElement* root = doc.RootElement();
  if (root && std::string(root->Name()) == "robot") {
    throw Error("bad_mjcf",
                "root element is <robot>: this is a URDF; MuJoCo 2.2.2 reads URDF only with the "
                "compiler options doasido sets on import: run `" + UrdfImportCommand(label) +
                    "` and use the MJCF and description it writes",
                {.file = label});
  }
  if (!root || std::string(root->Name()) != "mujoco") {
    throw Error("bad_mjcf", "root element is not <mujoco>", {.file = label});
  }
  PreparedMjcf out;
  StaticPass(root, label, out.changes);
  InlineIncludes(root, doc, base_dir, out.changes, 0);
  AbsolutizeAssets(root, base_dir);
  LimitedPass(root, out.changes);
  ModelPass(doc, label, out.changes);
  StripMarks(root);
  out.xml = Print(doc);
  return out;
}

PreparedMjcf PrepareMjcf(const std::filesystem::path& path) {
  return PrepareMjcfText(ReadFileOrThrow(path, "bad_mjcf", "cannot read MJCF file"), std::filesystem::absolute(path).parent_path(), path.string());
}

}  // namespace doasido::retarget
