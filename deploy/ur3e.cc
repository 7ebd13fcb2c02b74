#include "deploy/ur3e.h"

#include <cstdio>
#include <numbers>

#include <Eigen/LU>
#include <tinyxml2.h>

#include "core/error.h"
#include "robot/mjcf_compat.h"
#include "robot/mjcf_text.h"

namespace doasido::deploy {
namespace {

using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;
using tinyxml2::XMLNode;

std::string Fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.12g", v);
  return buf;
}

std::string Vec(double x, double y, double z) { return Fmt(x) + " " + Fmt(y) + " " + Fmt(z); }

std::string QuatText(const Quat& q) {
  return Fmt(q.w()) + " " + Fmt(q.x()) + " " + Fmt(q.y()) + " " + Fmt(q.z());
}

// Link radii (m) by joint: the UR3e's housings are ~9 cm across at the base
// and ~6 cm at the wrists.
constexpr std::array<double, 6> kRadius{0.045, 0.045, 0.038, 0.032, 0.032, 0.032};

}  // namespace

ArmLimits Ur3eLimits() {
  constexpr double kTwoPi = 2 * std::numbers::pi, kDeg = std::numbers::pi / 180;
  ArmLimits l;
  for (int i = 0; i < 6; ++i) {
    l.lower[i] = -kTwoPi;
    l.upper[i] = kTwoPi;
    l.max_speed[i] = (i < 3 ? 180 : 360) * kDeg;
    l.max_acceleration[i] = 5.0;
  }
  return l;
}

const std::array<const char*, 6>& Ur3eJointNames() {
  static const std::array<const char*, 6> names{"shoulder_pan", "shoulder_lift", "elbow",
                                                "wrist_1",      "wrist_2",       "wrist_3"};
  return names;
}

Pose DhForwardPose(const ArmQ& q, const DhParameters& dh) {
  const Mat4 m = DhForward<double>(q.data(), dh);
  return {Quat(Mat3(m.topLeftCorner<3, 3>())).normalized(), m.topRightCorner<3, 1>()};
}

std::array<Mat4, 7> DhFrames(const ArmQ& q, const DhParameters& dh) {
  std::array<Mat4, 7> out;
  out[0] = Mat4::Identity();
  for (int i = 0; i < 6; ++i) {
    DhParameters one;  // frame i+1 from frame i: the product's i-th factor alone
    ArmQ qi = ArmQ::Zero();
    qi[0] = q[i];
    one.d = {dh.d[i], 0, 0, 0, 0, 0};
    one.a = {dh.a[i], 0, 0, 0, 0, 0};
    one.alpha = {dh.alpha[i], 0, 0, 0, 0, 0};
    out[i + 1] = out[i] * DhForward<double>(qi.data(), one);
  }
  return out;
}

std::array<Vec3, 7> DhOrigins(const ArmQ& q, const DhParameters& dh) {
  const std::array<Mat4, 7> frames = DhFrames(q, dh);
  std::array<Vec3, 7> out;
  for (int i = 0; i < 7; ++i) out[i] = frames[i].topRightCorner<3, 1>();
  return out;
}

double Manipulability(const ArmQ& q, const DhParameters& dh) {
  const std::array<Mat4, 7> f = DhFrames(q, dh);
  const Vec3 end = f[6].topRightCorner<3, 1>();
  Eigen::Matrix<double, 6, 6> j;
  for (int i = 0; i < 6; ++i) {
    const Vec3 z = f[i].block<3, 1>(0, 2), o = f[i].topRightCorner<3, 1>();
    j.block<3, 1>(0, i) = z.cross(end - o);
    j.block<3, 1>(3, i) = z;
  }
  const double a2 = std::abs(dh.a[1]), a3 = std::abs(dh.a[2]);
  return std::abs(j.determinant()) / (a2 * a3 * (a2 + a3 + std::abs(dh.d[4])));
}

const std::array<double, 6>& Ur3eLinkRadii() { return kRadius; }

std::string Ur3eMjcf(const Pose& base, const DhParameters& dh, const ArmLimits& limits) {
  XMLDocument doc;
  XMLElement* root = doc.NewElement("mujoco");
  doc.InsertEndChild(root);
  root->SetAttribute("model", "ur3e");
  root->InsertNewChildElement("compiler")->SetAttribute("angle", "radian");
  XMLElement* parent = root->InsertNewChildElement("worldbody");
  XMLElement* body = parent->InsertNewChildElement("body");
  body->SetAttribute("name", "ur3e_base");
  body->SetAttribute("pos", Vec(base.t.x(), base.t.y(), base.t.z()).c_str());
  body->SetAttribute("quat", QuatText(base.q).c_str());
  XMLElement* plinth = body->InsertNewChildElement("geom");
  plinth->SetAttribute("type", "cylinder");
  plinth->SetAttribute("size", "0.064 0.02");
  plinth->SetAttribute("pos", "0 0 0.02");
  plinth->SetAttribute("contype", 0);
  plinth->SetAttribute("conaffinity", 0);
  plinth->SetAttribute("rgba", "0.3 0.3 0.32 1");
  Quat step = Quat::Identity();
  Vec3 offset = Vec3::Zero();
  for (int i = 0; i < 6; ++i) {
    XMLElement* link = body->InsertNewChildElement("body");
    link->SetAttribute("name", (std::string(Ur3eJointNames()[i]) + "_link").c_str());
    link->SetAttribute("pos", Vec(offset.x(), offset.y(), offset.z()).c_str());
    link->SetAttribute("quat", QuatText(step).c_str());
    XMLElement* joint = link->InsertNewChildElement("joint");
    joint->SetAttribute("name", Ur3eJointNames()[i]);
    joint->SetAttribute("type", "hinge");
    joint->SetAttribute("axis", "0 0 1");
    joint->SetAttribute("pos", "0 0 0");
    joint->SetAttribute("limited", "true");
    joint->SetAttribute("range", (Fmt(limits.lower[i]) + " " + Fmt(limits.upper[i])).c_str());
    joint->SetAttribute("damping", "1");
    joint->SetAttribute("armature", "0.01");
    XMLElement* geom = link->InsertNewChildElement("geom");
    geom->SetAttribute("name", (std::string(Ur3eJointNames()[i]) + "_capsule").c_str());
    geom->SetAttribute("type", "capsule");
    geom->SetAttribute("fromto", ("0 0 0 " + Vec(dh.a[i], 0, dh.d[i])).c_str());
    geom->SetAttribute("size", Fmt(kRadius[i]).c_str());
    geom->SetAttribute("contype", 0);
    geom->SetAttribute("conaffinity", 0);
    geom->SetAttribute("rgba", i % 2 ? "0.55 0.7 0.85 1" : "0.75 0.78 0.8 1");
    offset = Vec3(dh.a[i], 0, dh.d[i]);
    step = Quat(Eigen::AngleAxisd(dh.alpha[i], Vec3::UnitX()));
    body = link;
  }
  XMLElement* flange = body->InsertNewChildElement("body");
  flange->SetAttribute("name", "ur3e_flange");
  flange->SetAttribute("pos", Vec(offset.x(), offset.y(), offset.z()).c_str());
  flange->SetAttribute("quat", QuatText(step).c_str());
  XMLElement* inertial = flange->InsertNewChildElement("inertial");
  inertial->SetAttribute("pos", "0 0 0");
  inertial->SetAttribute("mass", "0.05");
  inertial->SetAttribute("diaginertia", "1e-5 1e-5 1e-5");
  return retarget::PrintMjcf(doc);
}

ArmHandModel BuildArmHandModel(const retarget::Embodiment& embodiment, const Pose& base,
                               const std::string& scene_xml,
                               const std::filesystem::path& scene_dir) {
  const std::string label = embodiment.model_path.string();
  ArmHandModel out;
  out.embodiment = embodiment;
  {
    retarget::Embodiment floating = embodiment;
    floating.floating_base = true;
    out.mount = retarget::BuildHandModel(floating).mount;
  }
  XMLDocument doc;
  retarget::ParseMjcfText(retarget::PrepareMjcf(embodiment.model_path).xml, label, doc);
  XMLElement* world = doc.RootElement()->FirstChildElement("worldbody");
  if (!world) throw Error("bad_mjcf", "model has no <worldbody>", {.file = label});
  std::vector<XMLElement*> hand_bodies;
  for (XMLElement* b = world->FirstChildElement("body"); b; b = b->NextSiblingElement("body")) {
    hand_bodies.push_back(b);
  }
  if (hand_bodies.empty()) throw Error("bad_mjcf", "no body under <worldbody>", {.file = label});

  XMLDocument arm;
  retarget::ParseMjcfText(Ur3eMjcf(base), "ur3e", arm);
  XMLElement* arm_base = arm.RootElement()->FirstChildElement("worldbody")->FirstChildElement("body");
  XMLElement* copy = arm_base->DeepClone(&doc)->ToElement();
  world->InsertEndChild(copy);
  XMLElement* flange = copy;
  while (flange && std::string(flange->Attribute("name")) != "ur3e_flange") {
    XMLElement* child = flange->FirstChildElement("body");
    flange = child;
  }
  if (!flange) throw Error("bad_mjcf", "arm model has no flange", {.file = "ur3e"});
  XMLElement* frame = flange->InsertNewChildElement("body");
  frame->SetAttribute("name", "doasido_hand_frame");
  frame->SetAttribute("quat", QuatText(Quat(out.mount)).c_str());
  for (XMLElement* b : hand_bodies) frame->InsertEndChild(b);  // moves the node
  if (!scene_xml.empty()) {
    const retarget::PreparedMjcf scene =
        retarget::PrepareMjcfText(scene_xml, scene_dir, (scene_dir / "scene").string());
    retarget::AppendRootChildren(doc, scene.xml, label);
  }
  out.xml = retarget::PrintMjcf(doc);
  out.model = retarget::CompileMjcfText(out.xml, label);
  const mjModel* m = out.model.get();
  for (int i = 0; i < 6; ++i) {
    const int j = retarget::NameToId(m, mjOBJ_JOINT, Ur3eJointNames()[i]);
    out.arm_qpos[i] = m->jnt_qposadr[j];
    out.arm_dof[i] = m->jnt_dofadr[j];
  }
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE) continue;
    const std::string name = mj_id2name(m, mjOBJ_JOINT, j) ? mj_id2name(m, mjOBJ_JOINT, j) : "";
    bool arm_joint = false;
    for (const char* a : Ur3eJointNames()) arm_joint |= name == a;
    if (arm_joint) continue;
    out.hand_joints.push_back(name);
    out.hand_qpos.push_back(m->jnt_qposadr[j]);
  }
  out.flange_body = retarget::NameToId(m, mjOBJ_BODY, "ur3e_flange");
  out.object_body = retarget::NameToId(m, mjOBJ_BODY, "object");
  if (out.object_body >= 0 && m->body_jntnum[out.object_body] > 0 &&
      m->jnt_type[m->body_jntadr[out.object_body]] == mjJNT_FREE) {
    out.object_qpos = m->jnt_qposadr[m->body_jntadr[out.object_body]];
  }
  return out;
}

}  // namespace doasido::deploy
