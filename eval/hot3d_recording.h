// Real hand-object ground truth from a HOT3D recording folder (the release's
// per-sequence export, e.g. ../shared/data/hot3d_sample/Aria/P0003_c701bd11),
// turned into a reconstruction (recon/reconstruction.h) that retargeting can
// track: the real-reference check of seed section 3.2.
//
// Files read (HOT3D conventions; REFERENCE.md):
//   dynamic_objects.csv      object_uid, timestamp[ns], t_wo xyz [m], q_wo wxyz
//   umetrack_hand_pose_trajectory.jsonl
//                            per line: timestamp_ns, hand_poses {"0": left,
//                            "1": right} with wrist_xform (t_xyz m, q_wxyz)
//                            and 22 joint_angles (rad)
//   umetrack_hand_user_profile.json   the hand model (umetrack_hand.h)
//   <object_library>/<uid>.glb        object models, metres
// HOT3D's world frame is gravity-aligned with z up (the resting objects'
// lowest points share one table height; tests/recon_hot3d_test.cc checks it).
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <string>

#include "core/mesh.h"
#include "eval/umetrack_hand.h"
#include "recon/reconstruction.h"

namespace doasido::recon {

struct Hot3dHandPose {
  std::array<double, kUmeTrackJoints> angles{};
  Pose wrist;  // hand -> world
};

struct Hot3dRecording {
  std::filesystem::path dir;
  UmeTrackHand hand_model;
  // uid -> timestamp (ns) -> object -> world
  std::map<std::string, std::map<long long, Pose>> objects;
  // "left" / "right" -> timestamp (ns) -> pose
  std::map<std::string, std::map<long long, Hot3dHandPose>> hands;
};

// A HOT3D pose table (dynamic_objects.csv, headset_trajectory.csv): uid ->
// timestamp (ns) -> pose (-> world). Throws Error("bad_hot3d") naming the
// file, line and column of a malformed row, Error("io") when unreadable.
std::map<std::string, std::map<long long, Pose>> ReadHot3dPoses(const std::filesystem::path& csv);

// Reads the three files above from `dir`. Throws Error("bad_hot3d") naming
// the file, line and field for a malformed row or non-finite value, and
// Error("io") for a missing file.
Hot3dRecording ReadHot3dRecording(const std::filesystem::path& dir);

struct Hot3dReferenceOptions {
  std::string hand = "right";   // "left" or "right"
  std::string object_uid;       // "" = the object the hand's fingertips come closest to
  // The mesh of an object the library has no model for (the sample lacks
  // some); empty = objects without a model are skipped. Set it with
  // `object_uid`, or it stands in for every object without a model.
  TriMesh stand_in;
  // Reflect the scene through the vertical plane y = 0 of the reference
  // frame: a left hand becomes a right hand (and the object its mirror
  // image), for robots that exist in one handedness only.
  bool mirror = false;
  // Both hands: the human right hand in right_joints and the left one in
  // left_joints (after `mirror`, the mirrored left hand is the right one);
  // `hand` then only chooses whose fingertips pick the object. A frame
  // where a hand has no pose is invalid for that hand.
  bool both_hands = false;
};

struct Hot3dReference {
  // The hand's joints in right_joints (see `hand`), or both hands (`both_hands`).
  Reconstruction reconstruction;
  TriMesh mesh;                   // the object, in its own frame
  std::string object_uid;
  std::string hand;               // the human hand the joints are from
  bool stand_in = false;          // `mesh` is the options' stand-in, not HOT3D's model
  bool mirrored = false;
  double mean_fingertip_distance = 0;  // m, fingertip nearest the object's surface, mean over frames
};

// The frames where both the hand and the object have a pose, in the
// reconstruction's frame: HOT3D's world moved so the object starts above
// the origin with its lowest point on z = 0 (floor_z = 0). The hand's
// OpenPose-21 joints come from the UmeTrack model (umetrack_hand.h).
// Throws Error("bad_hot3d") when the hand is absent, no object with a model
// in `object_library` is seen with it, or fewer than 2 frames are shared.
Hot3dReference Hot3dToReconstruction(const Hot3dRecording& recording,
                                     const std::filesystem::path& object_library,
                                     const Hot3dReferenceOptions& options = {});

}  // namespace doasido::recon
