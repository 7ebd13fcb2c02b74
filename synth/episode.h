// Scripted manipulation episodes: reach -> grasp (fingers close onto the
// object surface) -> manipulate (a verb) -> release -> retract, for one
// active hand, optionally with a second, idle hand. The object rests on the
// table (object-local z = 0 on the world plane z = 0) whenever it is not held.
// Everything is in the world frame (+z up, table top z = 0); the camera is
// chosen by the generator.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "core/mesh.h"
#include "synth/hand_model.h"

namespace doasido::synth {

enum class Verb { kPickPlace, kLiftRotate, kSlide, kStir };
const char* VerbName(Verb verb);

enum class LeaveFrame { kNone, kHand, kObject };

// Bimanual episodes (ScriptTwoHands).
enum class TwoHandTask { kNone, kHandover, kCarry, kHoldAndAct };
const char* TwoHandTaskName(TwoHandTask task);
// The task TwoHandTaskName gives `name`; throws Error("bad_config") otherwise.
TwoHandTask TwoHandTaskFromName(const std::string& name);

// How the active hand holds the object: kWrap, the palm against the object
// and the fingers closed round it until they touch (the thumb often ends on
// the rim, beside the fingers); kPinch, the object between the thumb tip
// and the index and middle fingertips on opposite sides, at the height
// kWrap grips, the ring and little fingers tucked in (a grasp whose
// contacts oppose, so a simulated robot hand copying it can lift the
// object; objects up to ~8 cm across).
enum class GraspType { kWrap, kPinch };
const char* GraspTypeName(GraspType type);
// The type GraspTypeName gives `name`; throws Error("bad_config") otherwise.
GraspType GraspTypeFromName(const std::string& name);

struct EpisodeSpec {
  Verb verb = Verb::kPickPlace;
  GraspType grasp = GraspType::kWrap;
  int frames = 90;
  Side active = Side::kRight;
  bool two_hands = false;
  double second_hand_offset = 0.2;       // m: how far to the side the second hand rests
  // A task for both hands (ScriptTwoHands); kNone: one active hand as above.
  // `verb`, `active`, `two_hands` and `leave` do not apply to the others.
  TwoHandTask two_hand_task = TwoHandTask::kNone;
  bool touch = true;                     // false: the hand hovers near the object, never touching
  bool static_scene = false;             // nothing moves: the hand rests beside the object
  LeaveFrame leave = LeaveFrame::kNone;  // who leaves the view mid-episode
  Vec2 object_xy = Vec2(0, 0.05);
  double object_yaw = 0;
  double approach_azimuth = -0.35;   // radians from world +x (right hand; mirrored for left)
  double approach_elevation = 0.55;  // radians above the horizontal
  double manipulation_scale = 1.0;   // scales verb amplitudes
};

// A grasp: the wrist in the object frame and the per-finger curl at which
// each finger first touches the object surface (thumb first).
struct Grasp {
  Pose wrist_in_object;
  std::array<double, 5> curl{};
  std::array<bool, 5> touching{};  // whether the finger reached the surface
  // The curls of the open hand the episode closes from (0: relaxed).
  std::array<double, 5> open{};
};

// Places the hand against the object (palm moved along the approach
// direction until the hand touches the surface, then backed off 2 mm) and
// closes each finger until its capsules touch the surface (bisection on the
// curl). `object` is object-local; the object is assumed at rest with yaw
// `object_yaw` (the approach direction is in the world).
Grasp SolveGrasp(const TriMesh& object, Side side, double azimuth, double elevation,
                 double object_yaw, const HandShape& shape = {});

// The kPinch grasp: the hand's opening (thumb tip to the midpoint of the
// index and middle tips) lies horizontal and across the approach, the wrist
// on the approach side, the radial side up; the thumb, index and middle
// close together (bisection on one closing parameter) until a capsule
// touches, the hand sliding across until thumb and fingers touch alike
// (backed off along the approach first when the open hand does not fit);
// ring and little fingers curl in fully unless that touches the object,
// then close until they touch. `Grasp::open` is the hand the episode
// approaches with. Same frame conventions as SolveGrasp.
Grasp SolvePinchGrasp(const TriMesh& object, Side side, double azimuth, double elevation,
                      double object_yaw, const HandShape& shape = {});

struct EpisodeFrame {
  Pose object_pose;                              // object-local -> world
  std::array<std::optional<HandPose>, 2> hands;  // by Side
  std::array<bool, 2> contact{};                 // hand touches the object
  std::string phase;                             // reach, approach, close, manipulate, ...
};

struct Episode {
  EpisodeSpec spec;
  Grasp grasp;
  std::vector<EpisodeFrame> frames;
};

Episode ScriptEpisode(const EpisodeSpec& spec, const TriMesh& object, const HandShape& shape = {});

// The tasks of EpisodeSpec::two_hand_task, the right hand approaching from
// its side and the left from the mirrored one; EpisodeFrame::contact is
// exact for each hand. Phases as fractions of the clip:
//  - kHandover: right reach 0-0.18, close 0.18-0.24, carry to the handover
//    pose (12 cm up, 8 cm to the left) 0.24-0.44; left reach 0.30-0.50,
//    close 0.50-0.56 (both hold 0.56-0.60); right opens 0.60-0.66 and
//    withdraws; left carries the object down 22 cm left of where it started
//    0.66-0.86, opens 0.86-0.92, withdraws.
//  - kCarry: both reach 0-0.18, close 0.18-0.24, lift (15 cm) and carry the
//    object 0.24-0.50, set it down 10 cm further 0.50-0.76, open 0.76-0.82,
//    withdraw.
//  - kHoldAndAct: the left hand steadies the object (reach 0-0.18, close
//    0.18-0.24, holds until 0.86, opens 0.86-0.92); the right hand grasps it
//    from above (approach 0.2 rad under the vertical) 0.24-0.48 and twists
//    back and forth about the object's vertical axis (+-0.4 rad, a lid
//    being turned) 0.48-0.76, opens 0.76-0.82, withdraws; the object never
//    moves.
Episode ScriptTwoHands(const EpisodeSpec& spec, const TriMesh& object, const HandShape& shape = {});

// Minimum-jerk profile s(t) = 10t^3 - 15t^4 + 6t^5 for t clamped to [0, 1].
double MinJerk(double t);

}  // namespace doasido::synth
