// A small right hand written as URDF for the import tests: a palm, a thumb
// (metacarpal, proximal, distal, tip link) and an index finger (knuckle,
// proximal, middle, distal, tip link), with box meshes: OBJ, one PLY (converted on
// import). Human-like proportions in the keypoint data's canonical frame
// (fingers +z, palm facing +x, thumb side +y); flexion is positive.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>

#include "tests/test_util.h"

namespace doasido::testing {

struct TwoFingerHandOptions {
  bool index_dip_continuous = false;   // an unlimited joint
  bool index_dip_mimics_pip = false;   // a <mimic> coupling
  std::string palm_mesh = "meshes/palm.ply";
  std::string root = "robot";          // root element name
};

// Box from (-hx,-hy,0) to (hx,hy,len) as OBJ or ASCII PLY text.
inline std::string BoxMeshText(double hx, double hy, double len, bool ply) {
  const double v[8][3] = {{-hx, -hy, 0}, {hx, -hy, 0}, {hx, hy, 0}, {-hx, hy, 0},
                          {-hx, -hy, len}, {hx, -hy, len}, {hx, hy, len}, {-hx, hy, len}};
  const int f[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                        {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::string s;
  char buf[128];
  if (ply) s = "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
               "property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& p : v) {
    std::snprintf(buf, sizeof(buf), ply ? "%g %g %g\n" : "v %g %g %g\n", p[0], p[1], p[2]);
    s += buf;
  }
  for (const auto& t : f) {
    if (ply) std::snprintf(buf, sizeof(buf), "3 %d %d %d\n", t[0], t[1], t[2]);
    else std::snprintf(buf, sizeof(buf), "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
    s += buf;
  }
  return s;
}

// A link; mass 0 leaves the <inertial> out (as tip frames usually are).
inline std::string HandLink(const std::string& name, const std::string& mesh, double mass) {
  return "  <link name=\"" + name + "\">\n" +
         (mass <= 0 ? std::string()
                    : "    <inertial><origin xyz=\"0 0 0.01\"/><mass value=\"" + std::to_string(mass) +
                          "\"/><inertia ixx=\"2e-6\" iyy=\"2e-6\" izz=\"1e-6\" ixy=\"0\" ixz=\"0\" "
                          "iyz=\"0\"/></inertial>\n") +
         (mesh.empty() ? "" : "    <visual><geometry><mesh filename=\"" + mesh + "\"/></geometry></visual>\n"
                              "    <collision><geometry><mesh filename=\"" + mesh +
                                  "\"/></geometry></collision>\n") +
         "  </link>\n";
}

inline std::string HandJoint(const std::string& name, const std::string& type, const std::string& parent,
                             const std::string& child, const std::string& xyz, const std::string& rpy,
                             const std::string& axis, double lo, double hi) {
  std::string s = "  <joint name=\"" + name + "\" type=\"" + type + "\"><parent link=\"" + parent +
                  "\"/><child link=\"" + child + "\"/><origin xyz=\"" + xyz + "\" rpy=\"" + rpy + "\"/>";
  if (type != "fixed") s += "<axis xyz=\"" + axis + "\"/>";
  if (type == "revolute") {
    s += "<limit lower=\"" + std::to_string(lo) + "\" upper=\"" + std::to_string(hi) +
         "\" effort=\"1\" velocity=\"3\"/>";
  }
  return s + "</joint>\n";
}

// Writes <dir>/two_finger.urdf and its meshes; returns the URDF path.
inline std::filesystem::path WriteTwoFingerHand(const std::filesystem::path& dir,
                                                const TwoFingerHandOptions& o = {}) {
  WriteFile(dir / "meshes/palm.ply", BoxMeshText(0.012, 0.04, 0.09, true));
  WriteFile(dir / "meshes/proximal.obj", BoxMeshText(0.009, 0.009, 0.045, false));
  WriteFile(dir / "meshes/middle.obj", BoxMeshText(0.0085, 0.0085, 0.028, false));
  WriteFile(dir / "meshes/distal.obj", BoxMeshText(0.008, 0.008, 0.022, false));
  WriteFile(dir / "meshes/metacarpal.obj", BoxMeshText(0.011, 0.011, 0.04, false));
  std::string u = "<?xml version=\"1.0\"?>\n<" + o.root + " name=\"two_finger\">\n";
  u += HandLink("palm", o.palm_mesh, 0.3);
  u += HandLink("thumb_metacarpal", "meshes/metacarpal.obj", 0.03);
  u += HandLink("thumb_proximal", "meshes/proximal.obj", 0.02);
  u += HandLink("thumb_distal", "meshes/distal.obj", 0.01);
  u += HandLink("thumb_tip", "", 0);
  u += HandLink("index_knuckle", "", 0.005);
  u += HandLink("index_proximal", "meshes/proximal.obj", 0.02);
  u += HandLink("index_middle", "meshes/middle.obj", 0.015);
  u += HandLink("index_distal", "meshes/distal.obj", 0.01);
  u += HandLink("index_tip", "", 0);
  u += HandJoint("thumb_cmc_fe", "revolute", "palm", "thumb_metacarpal", "0.008 0.022 0.02", "-0.8 0 0",
                 "0 1 0", -0.2, 1.9);
  u += HandJoint("thumb_mcp_fe", "revolute", "thumb_metacarpal", "thumb_proximal", "0 0 0.04", "0 0 0",
                 "0 1 0", -0.5, 1.4);
  u += HandJoint("thumb_ip", "revolute", "thumb_proximal", "thumb_distal", "0 0 0.035", "0 0 0", "0 1 0",
                 0, 1.7);
  u += HandJoint("thumb_tip_fixed", "fixed", "thumb_distal", "thumb_tip", "0 0 0.024", "0 0 0", "", 0, 0);
  u += HandJoint("index_mcp_aa", "revolute", "palm", "index_knuckle", "0 0.026 0.09", "0 0 0", "1 0 0",
                 -0.35, 0.35);
  u += HandJoint("index_mcp_fe", "revolute", "index_knuckle", "index_proximal", "0 0 0", "0 0 0", "0 1 0",
                 -0.2, 1.6);
  u += HandJoint("index_pip", "revolute", "index_proximal", "index_middle", "0 0 0.045", "0 0 0", "0 1 0",
                 0, 1.75);
  u += HandJoint("index_dip", o.index_dip_continuous ? "continuous" : "revolute", "index_middle",
                 "index_distal", "0 0 0.028", "0 0 0", "0 1 0", 0, 1.4);
  if (o.index_dip_mimics_pip) {
    const size_t at = u.find("<child link=\"index_distal\"/>");
    u.insert(at, "<mimic joint=\"index_pip\" multiplier=\"0.8\"/>");
  }
  u += HandJoint("index_tip_fixed", "fixed", "index_distal", "index_tip", "0 0 0.024", "0 0 0", "", 0, 0);
  u += "</" + o.root + ">\n";
  const std::filesystem::path path = dir / "two_finger.urdf";
  WriteFile(path, u);
  return path;
}

}  // namespace doasido::testing
