// The seed's arm, a Universal Robots UR3e, from its published DH parameters
// (REFERENCE.md section 5), and the arm with the project's hand on its flange.
//
// Kinematics (standard DH): the flange pose in the base frame is
//   T = prod_i Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i),   i = 1..6,
// with d = (0.15185, 0, 0, 0.13105, 0.08535, 0.0921), a = (0, -0.24355,
// -0.2132, 0, 0, 0), alpha = (pi/2, 0, 0, pi/2, -pi/2, 0); zero joint
// angles are the DH zero (UR's own convention, arm stretched along -x).
//
// The MJCF realises the same chain with one body per joint: body i carries
// hinge i about its local z at its origin, and its child sits at
// pos (a_i, 0, d_i), quat Rx(alpha_i) -- the DH transform after Rz(q_i).
// Links are capsules between successive origins. The flange body
// "ur3e_flange" holds "doasido_hand_frame", rotated by the hand's canonical
// mount (embodiment.h), under which the hand's bodies hang. So the flange
// pose plays exactly the role of the floating wrist ("doasido_wrist_mount")
// the retargeting solved for, and a trajectory's wrist pose is the flange
// target of the arm's inverse kinematics.
#pragma once

#include <array>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <numbers>

#include <Eigen/Core>

#include "core/geometry.h"
#include "robot/embodiment.h"
#include "robot/mj_model.h"

namespace doasido::deploy {

using ArmQ = Eigen::Matrix<double, 6, 1>;

struct DhParameters {
  std::array<double, 6> d{0.15185, 0, 0, 0.13105, 0.08535, 0.0921};
  std::array<double, 6> a{0, -0.24355, -0.2132, 0, 0, 0};
  std::array<double, 6> alpha{std::numbers::pi / 2, 0, 0, std::numbers::pi / 2,
                              -std::numbers::pi / 2, 0};
};

struct ArmLimits {
  std::array<double, 6> lower{};      // rad
  std::array<double, 6> upper{};      // rad
  std::array<double, 6> max_speed{};  // rad/s
  std::array<double, 6> max_acceleration{};  // rad/s^2
};

// UR3e: every joint +-360 degrees; 180 deg/s base, shoulder, elbow; 360 deg/s
// wrists. The arm itself limits torques, not accelerations; 5 rad/s^2 per
// joint is what Universal Robots' own ROS driver gives MoveIt for time
// parameterisation (ur_moveit_config joint_limits.yaml, "chosen
// conservatively").
ArmLimits Ur3eLimits();
// Joint names in order: shoulder_pan, shoulder_lift, elbow, wrist_1, wrist_2, wrist_3.
const std::array<const char*, 6>& Ur3eJointNames();

// Flange pose in the base frame by the DH product above. Templated so the
// inverse kinematics can differentiate it (Ceres Jets).
template <typename T>
Eigen::Matrix<T, 4, 4> DhForward(const T* q, const DhParameters& dh = {}) {
  Eigen::Matrix<T, 4, 4> m = Eigen::Matrix<T, 4, 4>::Identity();
  for (int i = 0; i < 6; ++i) {
    using std::cos;
    using std::sin;
    const T c = cos(q[i]), s = sin(q[i]);
    const double ca = std::cos(dh.alpha[i]), sa = std::sin(dh.alpha[i]);
    Eigen::Matrix<T, 4, 4> a;
    a << c, -s * ca, s * sa, T(dh.a[i]) * c,
         s, c * ca, -c * sa, T(dh.a[i]) * s,
         T(0), T(sa), T(ca), T(dh.d[i]),
         T(0), T(0), T(0), T(1);
    m = (m * a).eval();
  }
  return m;
}
Pose DhForwardPose(const ArmQ& q, const DhParameters& dh = {});

// The origins of the DH frames 0..6 in the base frame at `q` (0: the base,
// 6: the flange); link i (0-based) runs from origin i to origin i + 1.
std::array<Vec3, 7> DhOrigins(const ArmQ& q, const DhParameters& dh = {});
// The DH frames 0..6 themselves (base->frame i).
std::array<Mat4, 7> DhFrames(const ArmQ& q, const DhParameters& dh = {});

// Distance from singularities: |det J| of the 6x6 geometric Jacobian
// (independent of the reference point), divided by |a2 a3| (|a2| + |a3| +
// d5), its bound for a UR arm (det J = s3 s5 a2 a3 (c2 a2 + c23 a3 + s234
// d5)), so 0 at the elbow, wrist and shoulder singularities and at most 1.
double Manipulability(const ArmQ& q, const DhParameters& dh = {});
// The links' capsule radii (m), the MJCF's and the collision check's.
const std::array<double, 6>& Ur3eLinkRadii();

// MJCF of the bare arm (base body "ur3e_base" at `base`, flange body
// "ur3e_flange"), 2.2.2-compatible, joint ranges from `limits`.
std::string Ur3eMjcf(const Pose& base = {}, const DhParameters& dh = {},
                     const ArmLimits& limits = Ur3eLimits());

struct ArmHandModel {
  retarget::Embodiment embodiment;
  std::string xml;        // self-contained MJCF: arm + hand (+ scene)
  retarget::ModelPtr model;
  std::array<int, 6> arm_qpos{};  // qpos addresses of the six arm joints
  std::array<int, 6> arm_dof{};
  std::vector<std::string> hand_joints;  // the hand's 1-DoF joints, qpos order
  std::vector<int> hand_qpos;
  int flange_body = -1;
  int object_body = -1;   // body "object" of the scene, or -1
  int object_qpos = -1;   // its free joint's qpos address, or -1
  Mat3 mount = Mat3::Identity();
};

// The arm at `base` (in the scene's world frame) with `embodiment`'s hand on
// its flange (left or right variant is the embodiment's), and optionally a
// scene (<mujoco> text whose children are merged; relative paths against
// `scene_dir`, as retarget::BuildHandModel). Arm links do not collide (the
// replay drives the arm kinematically; see plan.h). Throws Error("bad_mjcf").
ArmHandModel BuildArmHandModel(const retarget::Embodiment& embodiment, const Pose& base,
                               const std::string& scene_xml = {},
                               const std::filesystem::path& scene_dir = {});

}  // namespace doasido::deploy
