#include "robot/hand_description.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>

#include "core/error.h"
#include "robot/mj_model.h"

namespace doasido::retarget {
namespace {

// Hinges within this angle of a chain's distal hinge count as flexion.
const double kFlexionCos = std::cos(35.0 * M_PI / 180.0);

Vec3 V(const mjtNum* p) { return Vec3(p[0], p[1], p[2]); }
Mat3 M(const mjtNum* p) { return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(p); }
std::string Name(const mjModel* m, int type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? n : std::string(type == mjOBJ_BODY ? "body" : "joint") + std::to_string(id);
}

// max over the geom's surface of x . dir, or nothing for planes and height fields.
std::optional<double> GeomSupport(const mjModel* m, const mjData* d, int g, const Vec3& dir) {
  const Vec3 c = V(d->geom_xpos + 3 * g);
  const Vec3 u = M(d->geom_xmat + 9 * g).transpose() * dir;
  const mjtNum* s = m->geom_size + 3 * g;
  double h = 0;
  switch (m->geom_type[g]) {
    case mjGEOM_SPHERE: h = s[0]; break;
    case mjGEOM_CAPSULE: h = s[0] + s[1] * std::abs(u.z()); break;
    case mjGEOM_CYLINDER: h = s[1] * std::abs(u.z()) + s[0] * std::hypot(u.x(), u.y()); break;
    case mjGEOM_BOX: h = s[0] * std::abs(u.x()) + s[1] * std::abs(u.y()) + s[2] * std::abs(u.z()); break;
    case mjGEOM_ELLIPSOID: h = Vec3(s[0] * u.x(), s[1] * u.y(), s[2] * u.z()).norm(); break;
    case mjGEOM_MESH: {
      const int id = m->geom_dataid[g];
      h = -std::numeric_limits<double>::infinity();
      for (int i = 0; i < m->mesh_vertnum[id]; ++i) {
        const float* v = m->mesh_vert + 3 * (m->mesh_vertadr[id] + i);
        h = std::max(h, v[0] * u.x() + v[1] * u.y() + v[2] * u.z());
      }
      break;
    }
    default: return std::nullopt;
  }
  return c.dot(dir) + h;
}

std::optional<double> BodySupport(const mjModel* m, const mjData* d, int b, const Vec3& dir) {
  std::optional<double> best;
  for (int g = m->body_geomadr[b]; g >= 0 && g < m->body_geomadr[b] + m->body_geomnum[b]; ++g) {
    const auto h = GeomSupport(m, d, g, dir);
    if (h && (!best || *h > *best)) best = h;
  }
  return best;
}

std::vector<int> HingesOf(const mjModel* m, int b) {
  std::vector<int> out;
  for (int j = m->body_jntadr[b]; j >= 0 && j < m->body_jntadr[b] + m->body_jntnum[b]; ++j) {
    if (m->jnt_type[j] == mjJNT_HINGE) out.push_back(j);
  }
  return out;
}

// Bodies from `b` up to (excluding) `stop`, distal first.
std::vector<int> PathUp(const mjModel* m, int b, int stop) {
  std::vector<int> path;
  for (; b > 0 && b != stop; b = m->body_parentid[b]) path.push_back(b);
  return path;
}

int CountHinges(const mjModel* m, const std::vector<int>& bodies) {
  int n = 0;
  for (int b : bodies) n += static_cast<int>(HingesOf(m, b).size());
  return n;
}

int CommonAncestor(const mjModel* m, const std::vector<int>& bodies) {
  std::vector<int> first = PathUp(m, bodies.front(), 0);
  first.push_back(0);
  for (int candidate : first) {
    bool all = true;
    for (int b : bodies) {
      int x = b;
      while (x > 0 && x != candidate) x = m->body_parentid[x];
      all &= x == candidate;
    }
    if (all) return candidate;
  }
  return 0;
}

// The leaves whose path below the common ancestor of all such leaves holds a
// hinge; iterated because dropping a static leaf can lower the ancestor.
std::vector<int> FingerLeaves(const mjModel* m, int* palm) {
  std::vector<int> children(m->nbody, 0);
  for (int b = 1; b < m->nbody; ++b) children[m->body_parentid[b]]++;
  std::vector<int> leaves;
  for (int b = 1; b < m->nbody; ++b) {
    if (children[b] == 0) leaves.push_back(b);
  }
  while (!leaves.empty()) {
    *palm = CommonAncestor(m, leaves);
    std::vector<int> kept;
    for (int b : leaves) {
      if (CountHinges(m, PathUp(m, b, *palm)) > 0) kept.push_back(b);
    }
    if (kept.size() == leaves.size()) break;
    leaves = kept;
  }
  return leaves;
}

Vec3 JointAnchor(const mjData* d, int j) { return V(d->xanchor + 3 * j); }
Vec3 JointAxis(const mjData* d, int j) { return V(d->xaxis + 3 * j); }

HandChain MakeChain(const mjModel* m, const mjData* d, int leaf, int palm) {
  HandChain c;
  std::vector<int> path = PathUp(m, leaf, palm);
  std::reverse(path.begin(), path.end());
  c.bodies = path;
  for (int b : path) {
    for (int j : HingesOf(m, b)) c.joints.push_back(j);
  }
  const Vec3 distal_axis = JointAxis(d, c.joints.back());
  for (int j : c.joints) {
    if (std::abs(JointAxis(d, j).dot(distal_axis)) >= kFlexionCos) c.flexion.push_back(j);
  }
  c.tip_body = leaf;
  // The finger's direction: from the last hinge to the distal body, or along
  // the segment before the last hinge when the distal body sits on it
  // (Allegro), or from the first hinge.
  const Vec3 pos = V(d->xpos + 3 * leaf);
  const size_t n = c.joints.size();
  Vec3 dir = pos - JointAnchor(d, c.joints[n - 1]);
  if (dir.norm() < 5e-3 && n >= 2) dir = JointAnchor(d, c.joints[n - 1]) - JointAnchor(d, c.joints[n - 2]);
  if (dir.norm() < 5e-3) dir = pos - JointAnchor(d, c.joints.front());
  if (dir.norm() < 1e-9) return c;
  dir.normalize();
  const auto h = BodySupport(m, d, leaf, dir);
  const double along = h ? std::max(0.0, *h - pos.dot(dir)) : 0.0;
  c.tip_offset = M(d->xmat + 9 * leaf).transpose() * (dir * along);
  return c;
}

Vec3 Knuckle(const mjData* d, const HandChain& c) {
  return JointAnchor(d, c.flexion.empty() ? c.joints.front() : c.flexion.front());
}
Vec3 FlexAxis(const mjData* d, const HandChain& c) { return JointAxis(d, c.joints.back()); }

// Index of the thumb in `chains` (see the header), with the reason in `note`.
size_t FindThumb(const mjData* d, const std::vector<HandChain>& chains, int palm, std::string* note) {
  size_t best = 0;
  if (chains.size() >= 3) {
    std::vector<double> score(chains.size(), 0);
    for (size_t i = 0; i < chains.size(); ++i) {
      for (size_t j = 0; j < chains.size(); ++j) {
        if (i != j) score[i] += 1 - std::abs(FlexAxis(d, chains[i]).dot(FlexAxis(d, chains[j])));
      }
      score[i] /= chains.size() - 1;
      if (score[i] > score[best]) best = i;
    }
    *note = "thumb: the chain whose flexion axis is least parallel to the others' (mean 1-|cos| " +
            std::to_string(score[best]) + ")";
  } else {
    const Vec3 origin = V(d->xpos + 3 * palm);
    for (size_t i = 1; i < chains.size(); ++i) {
      if ((Knuckle(d, chains[i]) - origin).norm() < (Knuckle(d, chains[best]) - origin).norm()) best = i;
    }
    *note = "thumb: of two chains, the one whose knuckle is nearest the palm's origin";
  }
  return best;
}

// Non-thumb chains ordered across the palm from the thumb's side.
void OrderFingers(const mjData* d, std::vector<HandChain>& others, const HandChain& thumb) {
  Vec3 lateral = Vec3::Zero();
  for (const HandChain& c : others) {
    const Vec3 a = FlexAxis(d, c);
    lateral += lateral.dot(a) < 0 ? -a : a;
  }
  if (lateral.norm() < 1e-9) return;
  lateral.normalize();
  double mean = 0;
  for (const HandChain& c : others) mean += Knuckle(d, c).dot(lateral) / others.size();
  const double side = Knuckle(d, thumb).dot(lateral) >= mean ? 1.0 : -1.0;
  std::stable_sort(others.begin(), others.end(), [&](const HandChain& a, const HandChain& b) {
    return side * Knuckle(d, a).dot(lateral) > side * Knuckle(d, b).dot(lateral);
  });
}

Vec3 WristOffset(const mjModel* m, const mjData* d, const HandStructure& s) {
  const Vec3 origin = V(d->xpos + 3 * s.palm);
  const Mat3 r = M(d->xmat + 9 * s.palm);
  Vec3 centroid = Vec3::Zero(), dir = Vec3::Zero();
  int n = 0;
  for (size_t i = 1; i < s.chains.size(); ++i) {
    const Vec3 k = Knuckle(d, s.chains[i]);
    centroid += k;
    dir += V(d->xpos + 3 * s.chains[i].tip_body) - k;
    ++n;
  }
  if (n == 0 || dir.norm() < 1e-9) return Vec3::Zero();
  centroid /= n;
  dir.normalize();
  const auto h = BodySupport(m, d, s.palm, -dir);
  const double t = h ? -*h : origin.dot(dir);  // lowest point of the palm along dir
  // A palm frame placed at the wrist (Shadow, Sharpa) is the wrist; one at
  // the knuckles (Allegro) is not.
  const double depth = centroid.dot(dir) - t, origin_depth = centroid.dot(dir) - origin.dot(dir);
  if (origin_depth >= 0.6 * depth) return Vec3::Zero();
  const Vec3 wrist = centroid + dir * (t - centroid.dot(dir));
  return r.transpose() * (wrist - origin);
}

}  // namespace

HandStructure AnalyzeHand(const mjModel* m, const std::string& label) {
  DataPtr data = MakeData(m);
  mjData* d = data.get();
  mj_kinematics(m, d);
  HandStructure s;
  std::vector<int> leaves = FingerLeaves(m, &s.palm);
  // One chain per child subtree of the palm: its deepest leaf.
  std::map<int, int> by_root;  // palm child -> chosen leaf
  for (int leaf : leaves) {
    const int root = PathUp(m, leaf, s.palm).back();
    auto it = by_root.find(root);
    auto key = [&](int b) {
      return std::make_pair(CountHinges(m, PathUp(m, b, s.palm)),
                            (V(d->xpos + 3 * b) - V(d->xpos + 3 * s.palm)).norm());
    };
    if (it == by_root.end() || key(leaf) > key(it->second)) by_root[root] = leaf;
  }
  if (by_root.size() < 2) {
    throw Error("bad_hand",
                "found " + std::to_string(by_root.size()) +
                    " finger chain(s) with hinge joints; a hand needs at least two (a thumb and a "
                    "finger). Check that the fingers' bodies were not fused away and their joints "
                    "are hinges",
                {.file = label});
  }
  std::vector<HandChain> chains;
  for (const auto& [root, leaf] : by_root) chains.push_back(MakeChain(m, d, leaf, s.palm));
  std::string note;
  const size_t thumb = FindThumb(d, chains, s.palm, &note);
  s.notes.push_back(note);
  HandChain t = chains[thumb];
  chains.erase(chains.begin() + thumb);
  OrderFingers(d, chains, t);
  t.finger = kFingerNames[0];
  s.chains.push_back(t);
  for (size_t i = 0; i < chains.size(); ++i) {
    chains[i].finger = i < 4 ? kFingerNames[i + 1] : "extra";
    s.chains.push_back(chains[i]);
  }
  if (chains.size() > 4) {
    s.notes.push_back(std::to_string(chains.size() - 4) +
                      " chain(s) beyond the pinky are not mapped to keypoints");
  }
  s.notes.push_back("fingers ordered across the palm from the thumb's side");
  s.wrist_offset = WristOffset(m, d, s);
  return s;
}

HandDescription DescribeHand(const mjModel* m, const HandStructure& s, const std::string& name,
                             const std::string& side, const std::string& model) {
  HandDescription out;
  Embodiment& e = out.embodiment;
  e.name = name;
  e.side = side;
  e.model = model;
  e.floating_base = true;
  e.scale = 0;
  auto add = [&](int keypoint, int body, const Vec3& pos, double weight, bool tip,
                 const std::string& note) {
    EmbodimentPoint p;
    p.keypoint = keypoint;
    p.body = Name(m, mjOBJ_BODY, body);
    for (int i = 0; i < 3; ++i) p.pos[i] = std::round(pos[i] * 1e5) / 1e5;  // 0.01 mm
    p.weight = weight;
    p.fingertip = tip;
    e.points.push_back(p);
    out.notes.push_back(note);
  };
  auto add_joint = [&](int keypoint, int j, double weight, const std::string& what) {
    add(keypoint, m->jnt_bodyid[j], V(m->jnt_pos + 3 * j), weight, false,
        what + ": anchor of joint " + Name(m, mjOBJ_JOINT, j));
  };
  add(0, s.palm, s.wrist_offset, 1.0, false,
      s.wrist_offset.isZero() ? "wrist: the palm's origin, at the palm's proximal end"
                              : "wrist: palm end opposite the fingers, on the line through the knuckles");
  for (size_t i = 0; i < s.chains.size(); ++i) {
    const HandChain& c = s.chains[i];
    if (c.finger == "extra") continue;
    const int base = i == 0 ? 1 : 1 + 4 * static_cast<int>(i);  // OpenPose first keypoint
    add(base + 3, c.tip_body, c.tip_offset, 1.0, true,
        c.finger + " fingertip: far end of the chain's distal body");
    const std::vector<int>& f = c.flexion;
    if (i == 0) {
      if (f.size() >= 2) add_joint(2, f[f.size() - 2], 0.3, "thumb MCP (second-last flexion joint)");
      if (!f.empty()) add_joint(3, f.back(), 0.2, "thumb IP (last flexion joint)");
      continue;
    }
    if (f.empty()) continue;
    add_joint(base, f[0], 0.5, c.finger + " knuckle (first flexion joint)");
    for (size_t k = 1; k < f.size() && k < 3; ++k) {
      add_joint(base + static_cast<int>(k), f[k], 0.1,
                c.finger + (k == 1 ? " PIP" : " DIP") + " (flexion joint " + std::to_string(k + 1) + ")");
    }
  }
  return out;
}

void WriteEmbodimentJson(const HandDescription& d, const std::string& comment,
                         const std::filesystem::path& path) {
  const Embodiment& e = d.embodiment;
  nlohmann::ordered_json j;
  j["name"] = e.name;
  j["side"] = e.side;
  j["model"] = e.model;
  j["floating_base"] = e.floating_base;
  j["scale"] = e.scale;
  j["comment"] = comment;
  j["points"] = nlohmann::ordered_json::array();
  for (size_t i = 0; i < e.points.size(); ++i) {
    const EmbodimentPoint& p = e.points[i];
    nlohmann::ordered_json q;
    q["keypoint"] = p.keypoint;
    if (!p.body.empty()) q["body"] = p.body;
    if (!p.site.empty()) q["site"] = p.site;
    q["pos"] = p.pos;
    q["weight"] = p.weight;
    if (p.fingertip) q["fingertip"] = true;
    if (i < d.notes.size()) q["note"] = d.notes[i];
    j["points"].push_back(q);
  }
  std::string text;
  try {
    text = j.dump(1);
  } catch (const nlohmann::json::type_error&) {
    // A body or site name that is not UTF-8 (found by hand_import_fuzz).
    throw Error("bad_hand", "a body or site name of the model is not valid UTF-8; rename it",
                {.file = path.string()});
  }
  std::ofstream out(path);
  out << text << "\n";
  if (!out) throw Error("io", "cannot write the hand description", {.file = path.string()});
}

int PointBody(const mjModel* m, const EmbodimentPoint& p) {
  if (!p.site.empty()) {
    const int s = NameToId(m, mjOBJ_SITE, p.site);
    return s < 0 ? -1 : m->site_bodyid[s];
  }
  return NameToId(m, mjOBJ_BODY, p.body);
}

}  // namespace doasido::retarget
