// What the dynamics-aware optimiser tracks (seed section 3.2), sampled at
// every simulation step of a hand + object scene:
//  - the kinematic retargeting's robot joint positions, which are also the
//    reference position targets (every hand joint carries a position
//    actuator, embodiment.h BuildHandModel);
//  - the reconstructed object pose;
//  - stage labels per step (seed: transition reward): "resting" while the
//    reconstructed object lies on the floor, "in hand" (per hand) while a
//    reconstructed hand is within epsilon of the object surface and the
//    object is off the floor; a step may be neither (the object in the air
//    with no hand near it: a reconstruction error the reward asks nothing
//    of; or on the floor with a hand near it, a grasp closing or opening,
//    where floor contact may end any step: the seed's "rest" is a hand away
//    from the object).
// Time: `warmup_steps` steps (seed "Warmup Steps") precede frame 0 and
// repeat it; step s is at time (s - warmup_steps) * dt from frame 0.
#pragma once

#include <cstdint>
#include <vector>

#include "core/geometry.h"
#include "core/mesh.h"
#include "recon/reconstruction.h"
#include "retarget/dynamic/knot_spline.h"
#include "retarget/kinematic/kinematic_retarget.h"
#include "robot/mj_model.h"

namespace doasido::retarget {

// The parts of a hand + object scene (BuildHandModel with a BuildObjectScene
// scene) the optimiser reads and writes.
struct SceneIndex {
  int object_body = -1;
  int object_qpos = -1;          // free joint: xyz then quaternion wxyz
  int object_dof = -1;
  int floor_geom = -1;
  std::vector<int> act_qpos;     // per actuator: qpos address of its joint
  std::vector<int> act_kind;     // per actuator: kBasePos, kBaseRot or kFinger
  std::vector<double> ctrl_lo, ctrl_hi;
  // Hands: the wrist mount bodies (kWristMountBody suffix) in body order;
  // per body, the index of the hand it belongs to (under that mount), or -1.
  std::vector<std::string> hands;
  std::vector<int> body_hand;
};
inline constexpr int kBasePos = 0, kBaseRot = 1, kFinger = 2;

// Throws Error("bad_mjcf") when the body "object" (with a free joint), the
// geom "floor" or a joint actuator is missing.
SceneIndex IndexScene(const mjModel* m);

struct DynamicReference {
  double dt = 0.005;       // simulation step, s
  double fps = 30;         // of the source frames
  int frames = 0;          // source frames
  int warmup_steps = 0;
  RowMatrix ctrl;          // (steps, nu) reference joint positions
  // (steps, nu) the position targets under which the actuators follow
  // `ctrl` (BuildReference): the optimiser's nominal controls. A position
  // actuator with joint damping d pulls by kp (u - q) - d qdot, so a joint
  // that should move lags its target unless the target leads it.
  RowMatrix feedforward;
  std::vector<Vec3> object_pos;    // (steps)
  std::vector<Quat> object_quat;   // (steps)
  // (steps) the hands that hold the object off the floor: bit h for
  // SceneIndex hand h; 0 while it rests.
  std::vector<uint8_t> in_hand;
  // (steps) 1 while the object rests on the floor.
  std::vector<uint8_t> resting;

  int steps() const { return static_cast<int>(ctrl.rows()); }
  // The simulation step at which source frame f is reached.
  int StepOfFrame(int f) const;
};

// Checks the reconstruction the optimiser is about to track: every frame
// marked valid is finite, at least one hand and one object frame are valid.
// Throws Error("bad_reference") naming `label` (file), the array and the frame.
void CheckReference(const recon::Reconstruction& r, const std::string& label);

// Object poses per frame with invalid frames filled by the nearest earlier
// valid frame (the first valid one before it).
std::vector<Pose> FilledObjectPoses(const recon::Reconstruction& r);

// Per frame: whether a valid reconstructed hand joint lies within `epsilon`
// of the object surface (`mesh` in the object frame, posed by `object`).
// Invalid hand frames are "resting". The first form labels the right hand.
std::vector<bool> LabelInHand(const recon::Reconstruction& r, const std::vector<Pose>& object,
                              const TriMesh& mesh, double epsilon);
std::vector<bool> LabelInHand(const std::vector<recon::Joints21>& joints, const std::vector<bool>& valid,
                              const std::vector<Pose>& object, const TriMesh& mesh, double epsilon);

// Per frame: whether the object (`mesh` posed by `object`) rests on the
// floor, its lowest point within `height` of z = 0 (the reconstruction's
// floor). A hand near a resting object is reaching for it or letting go:
// the object is not yet (or no longer) in that hand.
std::vector<bool> LabelResting(const std::vector<Pose>& object, const TriMesh& mesh, double height);

// Samples `kinematic` (HandTrajectory from KinematicRetargeter, whose
// qpos_names name the actuated joints), `object`, `in_hand` (one per
// frame: the hands near the object, bit h for SceneIndex hand h; 1 for the
// one hand of a one-hand scene) and `resting` (LabelResting) at the model's
// timestep, after `warmup_seconds` of frame 0. A resting frame holds in no
// hand, and a frame rests only with no hand near.
// Feed-forward targets: u = q + (d / kp) qdot for every actuated joint
// (its damping's lag at the reference velocity); the floating base, whose
// gains are critically damped (kp = I w^2, d = 2 I w: embodiment.h), also
// gets + qddot / w^2 and, on the slides, the gravity sag g / w^2.
// Derivatives are central differences over frames, interpolated like q.
// Throws Error("bad_reference") on a non-finite value or a size mismatch.
DynamicReference BuildReference(const mjModel* m,
                                const HandTrajectory& kinematic, const std::vector<Pose>& object,
                                const std::vector<uint8_t>& in_hand, const std::vector<bool>& resting,
                                double warmup_seconds);

}  // namespace doasido::retarget
