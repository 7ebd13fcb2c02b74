#include "retarget/dynamic/dynamic_reference.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"

namespace doasido::retarget {
namespace {

bool Finite(const Pose& p) { return p.t.allFinite() && p.q.coeffs().allFinite(); }

// Points spread over the mesh surface (vertices plus area-weighted samples),
// so a distance to the nearest one approximates the distance to the surface.
std::vector<Vec3> SurfaceSamples(const TriMesh& mesh, int count) {
  std::vector<Vec3> out;
  for (int v = 0; v < mesh.num_vertices(); ++v) out.push_back(mesh.vertices.row(v).transpose());
  std::vector<double> area(mesh.num_faces());
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Vec3 a = mesh.vertices.row(mesh.faces(f, 0)), b = mesh.vertices.row(mesh.faces(f, 1)),
               c = mesh.vertices.row(mesh.faces(f, 2));
    area[f] = 0.5 * (b - a).cross(c - a).norm();
  }
  if (area.empty()) return out;
  std::mt19937 rng(7);
  std::discrete_distribution<int> face(area.begin(), area.end());
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < count; ++i) {
    const int f = face(rng);
    double r1 = u(rng), r2 = u(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    const Vec3 a = mesh.vertices.row(mesh.faces(f, 0)), b = mesh.vertices.row(mesh.faces(f, 1)),
               c = mesh.vertices.row(mesh.faces(f, 2));
    out.push_back(a + r1 * (b - a) + r2 * (c - a));
  }
  return out;
}

}  // namespace

SceneIndex IndexScene(const mjModel* m) {
  SceneIndex s;
  s.object_body = NameToId(m, mjOBJ_BODY, "object");
  s.floor_geom = NameToId(m, mjOBJ_GEOM, "floor");
  if (s.object_body < 0 || s.floor_geom < 0 || m->body_jntnum[s.object_body] != 1 ||
      m->jnt_type[m->body_jntadr[s.object_body]] != mjJNT_FREE) {
    throw Error("bad_mjcf", "scene needs a free body 'object' and a geom 'floor'");
  }
  const int free = m->body_jntadr[s.object_body];
  s.object_qpos = m->jnt_qposadr[free];
  s.object_dof = m->jnt_dofadr[free];
  // Wrist mounts: the one hand's, or each hand's under its prefix.
  const auto is_mount = [&](int body) {
    const char* name = mj_id2name(m, mjOBJ_BODY, body);
    const std::string n = name ? name : "", suffix = kWristMountBody;
    return n.size() >= suffix.size() && n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  for (int a = 0; a < m->nu; ++a) {
    if (m->actuator_trntype[a] != mjTRN_JOINT) {
      throw Error("bad_mjcf", "actuator " + std::to_string(a) + " does not drive a joint");
    }
    const int j = m->actuator_trnid[2 * a];
    s.act_qpos.push_back(m->jnt_qposadr[j]);
    s.act_kind.push_back(!is_mount(m->jnt_bodyid[j])             ? kFinger
                         : m->jnt_type[j] == mjJNT_SLIDE ? kBasePos
                                                         : kBaseRot);
    const bool limited = m->actuator_ctrllimited[a];
    s.ctrl_lo.push_back(limited ? m->actuator_ctrlrange[2 * a] : -1e10);
    s.ctrl_hi.push_back(limited ? m->actuator_ctrlrange[2 * a + 1] : 1e10);
  }
  s.body_hand.assign(m->nbody, -1);
  for (int b = 1; b < m->nbody; ++b) {  // parents come before children
    if (is_mount(b)) {
      s.body_hand[b] = static_cast<int>(s.hands.size());
      s.hands.push_back(mj_id2name(m, mjOBJ_BODY, b));
    } else {
      s.body_hand[b] = s.body_hand[m->body_parentid[b]];
    }
  }
  return s;
}

int DynamicReference::StepOfFrame(int f) const {
  return std::min(steps() - 1, warmup_steps + static_cast<int>(std::lround(f / fps / dt)));
}

void CheckReference(const recon::Reconstruction& r, const std::string& label) {
  int hands = 0, objects = 0;
  for (int t = 0; t < r.frames(); ++t) {
    const auto bad = [&](const char* array) {
      throw Error("bad_reference", "non-finite values in frame " + std::to_string(t),
                  {.file = label, .field = array});
    };
    if (r.right_valid[t]) {
      if (!r.right_joints[t].allFinite()) bad("right_joints");
      ++hands;
    }
    if (t < static_cast<int>(r.object_valid.size()) && r.object_valid[t]) {
      if (!Finite(r.object_poses[t])) bad("object_poses");
      ++objects;
    }
  }
  if (!hands) throw Error("bad_reference", "no valid hand frame", {.file = label, .field = "right_valid"});
  if (!objects) throw Error("bad_reference", "no valid object frame", {.file = label, .field = "object_valid"});
}

std::vector<Pose> FilledObjectPoses(const recon::Reconstruction& r) {
  std::vector<Pose> out(r.frames());
  int first = 0;
  while (first < r.frames() && !r.object_valid[first]) ++first;
  for (int t = 0; t < r.frames(); ++t) {
    const bool valid = t < static_cast<int>(r.object_valid.size()) && r.object_valid[t];
    out[t] = valid ? r.object_poses[t] : t > first ? out[t - 1] : r.object_poses[first];
  }
  return out;
}

std::vector<bool> LabelInHand(const recon::Reconstruction& r, const std::vector<Pose>& object,
                              const TriMesh& mesh, double epsilon) {
  return LabelInHand(r.right_joints, r.right_valid, object, mesh, epsilon);
}

std::vector<bool> LabelInHand(const std::vector<recon::Joints21>& joints, const std::vector<bool>& valid,
                              const std::vector<Pose>& object, const TriMesh& mesh, double epsilon) {
  const std::vector<Vec3> surface = SurfaceSamples(mesh, 4000);
  std::vector<bool> out(valid.size(), false);
  for (size_t t = 0; t < valid.size(); ++t) {
    if (!valid[t]) continue;
    const Pose inv = object[t].Inverse();
    double best2 = 1e30;  // squared
    for (int k = 0; k < 21 && best2 >= epsilon * epsilon; ++k) {
      const Vec3 p = inv * Vec3(joints[t].row(k).transpose());
      for (const Vec3& s : surface) best2 = std::min(best2, (p - s).squaredNorm());
    }
    out[t] = best2 < epsilon * epsilon;
  }
  return out;
}

std::vector<bool> LabelResting(const std::vector<Pose>& object, const TriMesh& mesh, double height) {
  std::vector<bool> out(object.size(), false);
  if (mesh.num_vertices() == 0) return out;
  for (size_t t = 0; t < object.size(); ++t) {
    const Eigen::RowVector3d zrow = object[t].R().row(2);
    const double lowest = (mesh.vertices * zrow.transpose()).minCoeff() + object[t].t.z();
    out[t] = lowest < height;
  }
  return out;
}

// Per frame and actuator, the target's lead over the joint (see the
// header); row `frames` holds the lead of a joint at rest (gravity only).
RowMatrix FeedforwardOffsets(const mjModel* m, const HandTrajectory& kinematic,
                             const std::vector<int>& column) {
  const int frames = static_cast<int>(kinematic.qpos.size());
  RowMatrix lead = RowMatrix::Zero(frames + 1, m->nu);
  const SceneIndex index = IndexScene(m);
  DataPtr d = MakeData(m);
  mj_forward(m, d.get());  // joint axes in the world at qpos0
  const double h = 1.0 / kinematic.fps;
  for (int a = 0; a < m->nu; ++a) {
    const int joint = m->actuator_trnid[2 * a];
    const double kp = m->actuator_gainprm[a * mjNGAIN];
    const double damping = m->dof_damping[m->jnt_dofadr[joint]];
    if (kp <= 0 || damping <= 0) continue;
    const double tau = damping / kp;  // 2 / w for the base
    const bool base = index.act_kind[a] != kFinger;
    double sag = 0;
    if (index.act_kind[a] == kBasePos) {
      const Vec3 axis(d->xaxis[3 * joint], d->xaxis[3 * joint + 1], d->xaxis[3 * joint + 2]);
      sag = -Vec3(m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2]).dot(axis) * tau * tau / 4;
    }
    for (int f = 0; f < frames; ++f) {
      const double q0 = kinematic.qpos[std::max(0, f - 1)][column[a]];
      const double q1 = kinematic.qpos[f][column[a]];
      const double q2 = kinematic.qpos[std::min(frames - 1, f + 1)][column[a]];
      const double span = h * ((f > 0) + (f + 1 < frames));
      const double velocity = span > 0 ? (q2 - q0) / span : 0;
      const double acceleration = frames > 2 && f > 0 && f + 1 < frames ? (q2 - 2 * q1 + q0) / (h * h) : 0;
      lead(f, a) = tau * velocity + (base ? acceleration * tau * tau / 4 + sag : 0);
    }
    lead(frames, a) = sag;
  }
  return lead;
}

DynamicReference BuildReference(const mjModel* m,
                                const HandTrajectory& kinematic, const std::vector<Pose>& object,
                                const std::vector<uint8_t>& in_hand, const std::vector<bool>& resting,
                                double warmup_seconds) {
  const int frames = static_cast<int>(kinematic.qpos.size());
  if (frames == 0 || static_cast<int>(object.size()) != frames ||
      static_cast<int>(in_hand.size()) != frames || static_cast<int>(resting.size()) != frames) {
    throw Error("bad_reference", "hand, object and stage labels differ in length",
                {.field = "object_poses"});
  }
  // Column of each actuator's joint in the kinematic qpos.
  std::vector<int> column(m->nu, -1);
  for (int a = 0; a < m->nu; ++a) {
    const char* name = mj_id2name(m, mjOBJ_JOINT, m->actuator_trnid[2 * a]);
    const auto it = std::find(kinematic.qpos_names.begin(), kinematic.qpos_names.end(),
                              name ? name : "");
    if (it == kinematic.qpos_names.end()) {
      throw Error("bad_reference", std::string("no reference for joint ") + (name ? name : "?"),
                  {.field = "qpos_names"});
    }
    column[a] = static_cast<int>(it - kinematic.qpos_names.begin());
  }
  for (int f = 0; f < frames; ++f) {
    if (!kinematic.qpos[f].allFinite() || !Finite(object[f])) {
      throw Error("bad_reference", "non-finite reference in frame " + std::to_string(f),
                  {.field = kinematic.qpos[f].allFinite() ? "object_poses" : "qpos"});
    }
  }
  DynamicReference ref;
  ref.dt = m->opt.timestep;
  ref.fps = kinematic.fps;
  ref.frames = frames;
  ref.warmup_steps = static_cast<int>(std::lround(warmup_seconds / ref.dt));
  const int steps = ref.warmup_steps + static_cast<int>(std::lround((frames - 1) / ref.fps / ref.dt)) + 1;
  ref.ctrl.resize(steps, m->nu);
  ref.object_pos.resize(steps);
  ref.object_quat.resize(steps);
  ref.in_hand.resize(steps);
  ref.resting.resize(steps);
  const RowMatrix lead = FeedforwardOffsets(m, kinematic, column);  // (frames, nu)
  ref.feedforward.resize(steps, m->nu);
  for (int s = 0; s < steps; ++s) {
    const double u = std::max(0.0, (s - ref.warmup_steps) * ref.dt * ref.fps);
    const int f0 = std::min(frames - 1, static_cast<int>(u));
    const int f1 = std::min(frames - 1, f0 + 1);
    const double a = std::min(1.0, u - f0);
    for (int c = 0; c < m->nu; ++c) {
      ref.ctrl(s, c) = (1 - a) * kinematic.qpos[f0][column[c]] + a * kinematic.qpos[f1][column[c]];
      // Warmup holds frame 0 still: only the gravity part of its lead.
      const bool still = s < ref.warmup_steps;
      ref.feedforward(s, c) =
          ref.ctrl(s, c) + (still ? lead(frames, c) : (1 - a) * lead(f0, c) + a * lead(f1, c));
    }
    ref.object_pos[s] = (1 - a) * object[f0].t + a * object[f1].t;
    ref.object_quat[s] = object[f0].q.normalized().slerp(a, object[f1].q.normalized());
    const int nearest = a < 0.5 ? f0 : f1;
    // Seed stages: a hand near the object is no rest, even on the floor
    // (grasping or letting go: floor contact may end any step).
    ref.resting[s] = resting[nearest] && !in_hand[nearest];
    ref.in_hand[s] = resting[nearest] ? 0 : in_hand[nearest];
  }
  return ref;
}

}  // namespace doasido::retarget
