#include "synth/hand_model.h"

#include <cmath>

namespace doasido::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Rest splay of the fingers about the palm normal (positive towards the pinky).
constexpr std::array<double, 5> kRestSplay = {0.0, -0.10, 0.0, 0.09, 0.20};

Mat3 RotX(double a) { return Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix(); }
Mat3 RotZ(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }

// Base frame of the thumb: y along the rest thumb direction, flexion about x
// moves the tip across the palm towards the little finger.
Mat3 ThumbBase() {
  const Vec3 y = Vec3(0.60, 0.70, 0.38).normalized();
  Vec3 z = Vec3(-0.55, 0.0, 0.85);
  z = (z - z.dot(y) * y).normalized();
  Mat3 r;
  r.col(0) = y.cross(z);
  r.col(1) = y;
  r.col(2) = z;
  return r;
}

Vec3 AnyPerpendicular(const Vec3& u) {
  const Vec3 trial = std::abs(u.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return (trial - trial.dot(u) * u).normalized();
}

}  // namespace

Mat3 HandFrame(const Vec3& distal, const Vec3& palm_normal) {
  Mat3 r;
  r.col(0) = distal.cross(palm_normal);
  r.col(1) = distal;
  r.col(2) = palm_normal;
  return r;
}

HandJoints HandJointPositions(const HandPose& pose, Side side, const HandShape& shape) {
  HandJoints local;
  local.row(0).setZero();
  for (int f = 0; f < 5; ++f) {
    Mat3 r = f == 0 ? Mat3(ThumbBase() * RotZ(pose.abduct[0]))
                    : Mat3(RotZ(kRestSplay[f] + pose.abduct[f]));
    Vec3 p = shape.base[f];
    const int first = 1 + 4 * f;
    local.row(first) = p.transpose();
    for (int s = 0; s < 3; ++s) {
      r = r * RotX(pose.flex[f][s]);
      p += r * Vec3(0, shape.length[f][s], 0);
      local.row(first + 1 + s) = p.transpose();
    }
  }
  HandJoints out;
  for (int j = 0; j < 21; ++j) {
    Vec3 p = local.row(j).transpose() * shape.scale;
    if (side == Side::kLeft) p.x() = -p.x();
    out.row(j) = (pose.wrist * p).transpose();
  }
  return out;
}

std::vector<Capsule> HandCapsules(const HandJoints& joints, const HandPose& pose, Side side,
                                  const HandShape& shape) {
  (void)side;
  const double s = shape.scale;
  auto J = [&](int i) { return Vec3(joints.row(i).transpose()); };
  std::vector<Capsule> caps;
  // Fingers: three segments each, tapering.
  for (int f = 0; f < 5; ++f) {
    const int first = 1 + 4 * f;
    for (int k = 0; k < 3; ++k) {
      const double taper = 1.0 - 0.1 * k;
      caps.push_back({J(first + k), J(first + k + 1), shape.radius[f] * taper * s});
    }
  }
  // Palm: fan from the wrist to the finger bases plus transverse bars.
  const Vec3 wrist = J(0);
  const double rp = shape.palm_radius * s;
  for (int f = 1; f < 5; ++f) caps.push_back({wrist, J(1 + 4 * f), rp});
  caps.push_back({J(5), J(17), rp});
  caps.push_back({0.5 * (wrist + J(5)), 0.5 * (wrist + J(17)), rp});
  caps.push_back({J(1), J(5), rp * 0.8});  // thenar web
  caps.push_back({wrist, J(1), rp});
  // A short piece of forearm behind the wrist.
  const Vec3 distal = pose.wrist.R().col(1);
  caps.push_back({wrist - distal * 0.012 * s, wrist - distal * shape.forearm_length * s,
                  shape.wrist_radius * s});
  return caps;
}

TriMesh CapsulesMesh(const std::vector<Capsule>& capsules, std::vector<int>* capsule_of_face) {
  constexpr int kSeg = 12;   // around the axis
  constexpr int kRings = 4;  // per hemisphere, the equator included
  constexpr int kRingCount = 2 * kRings;
  constexpr int kVerts = kRingCount * kSeg + 2;
  constexpr int kFaces = 2 * kSeg + (kRingCount - 1) * kSeg * 2;
  TriMesh mesh;
  const int n = static_cast<int>(capsules.size());
  mesh.vertices.resize(n * kVerts, 3);
  mesh.faces.resize(n * kFaces, 3);
  if (capsule_of_face) capsule_of_face->assign(n * kFaces, 0);
  for (int c = 0; c < n; ++c) {
    const Capsule& cap = capsules[c];
    Vec3 axis = cap.b - cap.a;
    const double len = axis.norm();
    const Vec3 u = len > 1e-12 ? Vec3(axis / len) : Vec3::UnitZ();
    const Vec3 e1 = AnyPerpendicular(u);
    const Vec3 e2 = u.cross(e1);
    const int vb = c * kVerts;
    int v = vb;
    mesh.vertices.row(v++) = (cap.a - u * cap.radius).transpose();  // bottom pole
    for (int ring = 0; ring < kRingCount; ++ring) {
      const bool top = ring >= kRings;
      const double phi =
          top ? (ring - kRings) * (kPi / 2) / kRings : -kPi / 2 + (ring + 1) * (kPi / 2) / kRings;
      const Vec3 centre = top ? cap.b : cap.a;
      for (int k = 0; k < kSeg; ++k) {
        const double th = 2 * kPi * k / kSeg;
        const Vec3 dir =
            (std::cos(th) * e1 + std::sin(th) * e2) * std::cos(phi) + u * std::sin(phi);
        mesh.vertices.row(v++) = (centre + cap.radius * dir).transpose();
      }
    }
    mesh.vertices.row(v++) = (cap.b + u * cap.radius).transpose();  // top pole
    int f = c * kFaces;
    auto ring_v = [&](int ring, int k) { return vb + 1 + ring * kSeg + (k % kSeg); };
    // (e1, e2, u) is right-handed, so increasing k turns counter-clockwise
    // seen from +u; outward faces list (lower ring, upper ring) accordingly.
    for (int k = 0; k < kSeg; ++k) mesh.faces.row(f++) << vb, ring_v(0, k + 1), ring_v(0, k);
    for (int ring = 0; ring + 1 < kRingCount; ++ring) {
      for (int k = 0; k < kSeg; ++k) {
        mesh.faces.row(f++) << ring_v(ring, k), ring_v(ring, k + 1), ring_v(ring + 1, k + 1);
        mesh.faces.row(f++) << ring_v(ring, k), ring_v(ring + 1, k + 1), ring_v(ring + 1, k);
      }
    }
    const int top_pole = vb + kVerts - 1;
    for (int k = 0; k < kSeg; ++k) {
      mesh.faces.row(f++) << ring_v(kRingCount - 1, k), ring_v(kRingCount - 1, k + 1), top_pole;
    }
    if (capsule_of_face) {
      for (int i = c * kFaces; i < (c + 1) * kFaces; ++i) (*capsule_of_face)[i] = c;
    }
  }
  return mesh;
}

PosedHand PoseHand(const HandPose& pose, Side side, const HandShape& shape) {
  PosedHand out;
  out.joints = HandJointPositions(pose, side, shape);
  out.capsules = HandCapsules(out.joints, pose, side, shape);
  out.mesh = CapsulesMesh(out.capsules, &out.capsule_of_face);
  return out;
}

HandPose RelaxedPose(const Pose& wrist) {
  HandPose p;
  p.wrist = wrist;
  for (int f = 0; f < 5; ++f) SetFingerCurl(p, f, 0.0);
  p.abduct[0] = 0.0;
  return p;
}

void SetFingerCurl(HandPose& pose, int finger, double curl) {
  if (finger == 0) {
    pose.flex[0] = {0.15 + 0.75 * curl, 0.15 + 0.55 * curl, 0.10 + 0.75 * curl};
  } else {
    pose.flex[finger] = {0.15 + 1.30 * curl, 0.20 + 1.55 * curl, 0.10 + 1.10 * curl};
  }
}

}  // namespace doasido::synth
