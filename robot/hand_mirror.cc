#include "robot/hand_mirror.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <vector>

#include <tinyxml2.h>

#include "core/error.h"
#include "core/geometry.h"
#include "robot/mjcf_compat.h"
#include "robot/mjcf_text.h"

namespace doasido::retarget {
namespace {

using tinyxml2::XMLElement;

struct Reflection {
  int axis = 1;
  double angle_scale = M_PI / 180;  // the compiler's angle unit, in radians
  std::string eulerseq = "xyz";
  std::string label;

  Vec3 Point(Vec3 v) const {
    v[axis] = -v[axis];
    return v;
  }
  double Sign(int i) const { return i == axis ? -1.0 : 1.0; }
  // The quaternion of S R S.
  Quat Rotation(const Quat& q) const {
    const Vec3 v = -Point(q.vec());
    return Quat(q.w(), v.x(), v.y(), v.z());
  }
};

std::string ElementName(const XMLElement* e) {
  const char* name = e->Attribute("name");
  return std::string("<") + e->Name() + (name ? std::string(" name=\"") + name + "\"" : "") + ">";
}

std::vector<double> Numbers(const XMLElement* e, const char* attribute, size_t count,
                            const Reflection& r) {
  std::istringstream in(e->Attribute(attribute));
  std::vector<double> out;
  double x;
  while (in >> x) out.push_back(x);
  if (out.size() != count || !in.eof()) {
    throw Error("bad_mjcf", ElementName(e) + " " + attribute + " needs " + std::to_string(count) + " numbers",
                {.file = r.label, .field = attribute});
  }
  return out;
}

void SetNumbers(XMLElement* e, const char* attribute, const std::vector<double>& values) {
  std::string text;
  char buf[32];
  for (double v : values) {
    std::snprintf(buf, sizeof(buf), "%.12g", v == 0 ? 0.0 : v);  // no "-0"
    text += (text.empty() ? "" : " ") + std::string(buf);
  }
  e->SetAttribute(attribute, text.c_str());
}

// Reflects the vector attribute (count / 3 points of three numbers).
void ReflectPoints(XMLElement* e, const char* attribute, size_t count, const Reflection& r) {
  if (!e->Attribute(attribute)) return;
  std::vector<double> v = Numbers(e, attribute, count, r);
  for (size_t i = 0; i < count; i += 3) v[i + r.axis] = -v[i + r.axis];
  SetNumbers(e, attribute, v);
}

Quat EulerQuat(const std::vector<double>& angles, const Reflection& r) {
  Quat q = Quat::Identity();
  for (int i = 0; i < 3; ++i) {
    const char c = r.eulerseq[i];
    const int axis = std::tolower(c) - 'x';
    const Quat step(Eigen::AngleAxisd(angles[i] * r.angle_scale, Vec3::Unit(axis)));
    q = std::islower(c) ? Quat(q * step) : Quat(step * q);  // moving axes, else fixed ones
  }
  return q;
}

void ReflectOrientation(XMLElement* e, const Reflection& r) {
  if (e->Attribute("euler")) {
    const Quat q = r.Rotation(EulerQuat(Numbers(e, "euler", 3, r), r));
    e->DeleteAttribute("euler");
    SetNumbers(e, "quat", {q.w(), q.x(), q.y(), q.z()});
    return;
  }
  if (e->Attribute("quat")) {
    const std::vector<double> v = Numbers(e, "quat", 4, r);
    const Quat q = r.Rotation(Quat(v[0], v[1], v[2], v[3]));
    SetNumbers(e, "quat", {q.w(), q.x(), q.y(), q.z()});
  }
  if (e->Attribute("axisangle")) {
    std::vector<double> v = Numbers(e, "axisangle", 4, r);
    const Vec3 a = -r.Point(Vec3(v[0], v[1], v[2]));
    SetNumbers(e, "axisangle", {a.x(), a.y(), a.z(), v[3]});
  }
  if (e->Attribute("xyaxes")) {  // the columns of S R S: S R S e_i = s_i S (R e_i)
    std::vector<double> v = Numbers(e, "xyaxes", 6, r);
    const Vec3 x = r.Sign(0) * r.Point(Vec3(v[0], v[1], v[2]));
    const Vec3 y = r.Sign(1) * r.Point(Vec3(v[3], v[4], v[5]));
    SetNumbers(e, "xyaxes", {x.x(), x.y(), x.z(), y.x(), y.y(), y.z()});
  }
  if (e->Attribute("zaxis")) {
    // The compiler turns z onto zaxis by the shortest rotation, whose
    // mirror image is not the shortest rotation onto the mirrored axis
    // when z itself flips: written as the quaternion it means.
    const std::vector<double> v = Numbers(e, "zaxis", 3, r);
    const Vec3 z = Vec3(v[0], v[1], v[2]).normalized();
    const Quat q = z.z() < -1 + 1e-12 ? Quat(0, 1, 0, 0) : Quat::FromTwoVectors(Vec3::UnitZ(), z);
    const Quat m = r.Rotation(q);
    e->DeleteAttribute("zaxis");
    SetNumbers(e, "quat", {m.w(), m.x(), m.y(), m.z()});
  }
}

bool IsSlide(const XMLElement* joint) {
  const char* type = joint->Attribute("type");
  return type && std::strcmp(type, "slide") == 0;
}

void ReflectInertia(XMLElement* e, const Reflection& r) {
  if (!e->Attribute("fullinertia")) return;
  std::vector<double> v = Numbers(e, "fullinertia", 6, r);  // xx yy zz xy xz yz
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int k = 0; k < 3; ++k) {
    if ((pairs[k][0] == r.axis) != (pairs[k][1] == r.axis)) v[3 + k] = -v[3 + k];
  }
  SetNumbers(e, "fullinertia", v);
}

// Whether a <mesh> of class `cls` inherits a scale from the defaults.
bool InheritsMeshScale(const XMLElement* root, const char* cls) {
  const XMLElement* defaults = root->FirstChildElement("default");
  if (!defaults) return false;
  // Depth-first search for the default class, remembering the chain.
  std::vector<const XMLElement*> chain;
  std::function<bool(const XMLElement*)> find = [&](const XMLElement* d) {
    chain.push_back(d);
    const char* name = d->Attribute("class");
    if ((!cls && d == defaults) || (cls && name && std::strcmp(name, cls) == 0)) return true;
    for (const XMLElement* c = d->FirstChildElement("default"); c; c = c->NextSiblingElement("default")) {
      if (find(c)) return true;
    }
    chain.pop_back();
    return false;
  };
  for (const XMLElement* d = defaults; d; d = d->NextSiblingElement("default")) {
    if (find(d)) break;
  }
  for (const XMLElement* d : chain) {
    const XMLElement* mesh = d->FirstChildElement("mesh");
    if (mesh && mesh->Attribute("scale")) return true;
  }
  return false;
}

void ReflectMeshScale(XMLElement* mesh, const XMLElement* root, bool in_default, const Reflection& r) {
  if (!mesh->Attribute("scale")) {
    if (in_default || InheritsMeshScale(root, mesh->Attribute("class"))) return;
    mesh->SetAttribute("scale", "1 1 1");
  }
  std::vector<double> v = Numbers(mesh, "scale", 3, r);
  v[r.axis] = -v[r.axis];
  SetNumbers(mesh, "scale", v);
}

void ReflectElement(XMLElement* e, const XMLElement* root, bool in_default, const Reflection& r) {
  const std::string tag = e->Name();
  if (tag == "mesh") {
    ReflectMeshScale(e, root, in_default, r);
    return;
  }
  if (tag == "compiler" || tag == "option" || tag == "size" || tag == "visual" || tag == "statistic") return;
  ReflectPoints(e, "pos", 3, r);
  ReflectPoints(e, "anchor", 3, r);
  ReflectPoints(e, "fromto", 6, r);
  if (tag == "light") ReflectPoints(e, "dir", 3, r);
  ReflectOrientation(e, r);
  if (tag == "inertial") ReflectInertia(e, r);
  if (tag == "joint" && e->Attribute("axis")) {
    std::vector<double> a = Numbers(e, "axis", 3, r);
    const Vec3 m = r.Point(Vec3(a[0], a[1], a[2]));
    const Vec3 axis = IsSlide(e) ? m : Vec3(-m);
    SetNumbers(e, "axis", {axis.x(), axis.y(), axis.z()});
  }
}

void ReflectTree(XMLElement* e, const XMLElement* root, bool in_default, const Reflection& r) {
  for (XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
    const bool default_child = in_default || std::strcmp(c->Name(), "default") == 0;
    ReflectElement(c, root, default_child, r);
    ReflectTree(c, root, default_child, r);
  }
}

int AxisIndex(char axis) {
  if (axis < 'x' || axis > 'z') {
    throw Error("bad_config", std::string("mirror axis must be x, y or z, not ") + axis, {.field = "axis"});
  }
  return axis - 'x';
}

}  // namespace

std::string MirrorMjcf(const std::string& xml, char axis, const std::string& label) {
  Reflection r;
  r.axis = AxisIndex(axis);
  r.label = label;
  tinyxml2::XMLDocument doc;
  ParseMjcfText(xml, label, doc);
  XMLElement* root = doc.RootElement();
  for (const XMLElement* c = root->FirstChildElement("compiler"); c; c = c->NextSiblingElement("compiler")) {
    if (const char* angle = c->Attribute("angle")) r.angle_scale = std::strcmp(angle, "radian") == 0 ? 1.0 : M_PI / 180;
    if (const char* seq = c->Attribute("eulerseq")) r.eulerseq = seq;
  }
  if (r.eulerseq.size() != 3 || r.eulerseq.find_first_not_of("xyzXYZ") != std::string::npos) {
    throw Error("bad_mjcf", "compiler eulerseq must be three of x, y, z (either case)",
                {.file = label, .field = "eulerseq"});
  }
  ReflectTree(root, root, false, r);
  return PrintMjcf(doc);
}

std::string MirroredName(const std::string& name) {
  std::string out = name;
  if (const size_t at = out.find("right"); at != std::string::npos) {
    out.replace(at, 5, "left");
  } else if (const size_t at_left = out.find("left"); at_left != std::string::npos) {
    out.replace(at_left, 4, "right");
  } else {
    out += "_mirrored";
  }
  return out;
}

Embodiment MirrorEmbodiment(const Embodiment& hand, char axis, const std::string& name,
                            const std::string& model) {
  const int k = AxisIndex(axis);
  Embodiment out = hand;
  out.name = name;
  out.side = hand.side == "right" ? "left" : "right";
  out.model = model;
  for (EmbodimentPoint& p : out.points) p.pos[k] = p.pos[k] == 0 ? 0.0 : -p.pos[k];  // no "-0"
  return out;
}

MirroredHand MirrorHand(const Embodiment& hand, const std::filesystem::path& out_dir,
                        const MirrorOptions& options) {
  const std::string name = options.name.empty() ? MirroredName(hand.name) : options.name;
  const PreparedMjcf prepared = PrepareMjcf(hand.model_path);
  const std::string xml = MirrorMjcf(prepared.xml, options.axis, hand.model_path.string());
  MirroredHand out;
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  out.model = out_dir / (name + ".xml");
  out.description = out_dir / (name + ".json");
  out.embodiment = MirrorEmbodiment(hand, options.axis, name, out.model.filename().string());
  out.embodiment.model_path = std::filesystem::absolute(out.model);
  const auto write = [](const std::filesystem::path& path, const std::string& text) {
    std::ofstream file(path);
    file << text;
    if (!file) throw Error("io", "cannot write the mirrored hand", {.file = path.string()});
  };
  write(out.model, "<!-- " + hand.name + " (" + hand.model_path.string() + ") mirrored through " +
                       options.axis + " = 0 by `doasido hand mirror` -->\n" + xml);
  write(out.description, Json(out.embodiment).dump(1) + "\n");
  return out;
}

}  // namespace doasido::retarget
