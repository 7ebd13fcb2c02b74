// Real ground truth through the bundle: HOT3D's object trajectory
// (dynamic_objects.csv) and headset trajectory, expressed in the headset
// frame, with the object's real GLB model, written as a clip bundle and read
// back unchanged. Skipped when ../shared/data/hot3d_sample is absent.
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include <gtest/gtest.h>

#include "core/mesh.h"
#include "eval/hot3d_recording.h"
#include "recon/bundle/bundle.h"
#include "recon/bundle/conventions.h"
#include "recon/recon_metrics.h"
#include "synth/objects.h"
#include "tests/test_util.h"

namespace doasido::recon {
namespace {

using doasido::testing::SharedData;
using doasido::testing::TempDir;
using doasido::testing::ReadFile;
using doasido::testing::WriteFile;

const char kMouse[] = "265826671143948";

std::filesystem::path Sample() { return SharedData() / "hot3d_sample"; }
std::filesystem::path Recording() { return Sample() / "Aria" / "P0003_c701bd11"; }

std::map<long long, Pose> ReadPoses(const std::filesystem::path& csv, const std::string& uid) {
  return ReadHot3dPoses(csv).at(uid);
}

class Hot3dBundleTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(Recording() / "dynamic_objects.csv")) {
      GTEST_SKIP() << "HOT3D sample not found under " << Sample();
    }
  }
};

TEST_F(Hot3dBundleTest, ObjectTrajectoryAndModelRoundTrip) {
  const auto objects = ReadPoses(Recording() / "dynamic_objects.csv", kMouse);
  const auto headset = ReadPoses(Recording() / "headset_trajectory.csv", "5411364721403");
  ASSERT_GT(objects.size(), 10u);

  ClipBundle b;
  b.width = 1408;  // Aria RGB
  b.height = 1408;
  std::vector<long long> stamps;
  for (const auto& [stamp, world_object] : objects) {
    auto it = headset.find(stamp);
    if (it == headset.end()) continue;
    // object -> headset = (headset -> world)^-1 * (object -> world)
    b.object_poses.push_back(it->second.Inverse() * world_object);
    stamps.push_back(stamp);
  }
  ASSERT_EQ(stamps.size(), objects.size()) << "every object pose has a headset pose";
  b.frames = static_cast<int>(stamps.size());
  b.fps = 1e9 * (b.frames - 1) / static_cast<double>(stamps.back() - stamps.front());
  b.producers = {{"object_poses", "hot3d ground truth"}};

  const auto glb = Sample() / "object_library" / (std::string(kMouse) + ".glb");
  const TriMesh raw = LoadMesh(glb);
  b.object_mesh = raw;
  const double extent = (raw.Max() - raw.Min()).maxCoeff();
  EXPECT_GT(extent, 0.05) << "HOT3D models are in metres; a computer mouse is 5-15 cm long";
  EXPECT_LT(extent, 0.15);

  TempDir dir;
  WriteBundle(b, dir.path());
  const ClipBundle r = ReadBundle(dir.path());
  EXPECT_EQ(r.frames, b.frames);
  EXPECT_EQ(r.fps, b.fps);
  ASSERT_EQ(r.object_poses.size(), b.object_poses.size());
  for (size_t t = 0; t < b.object_poses.size(); ++t) {
    EXPECT_EQ(r.object_poses[t].t, b.object_poses[t].t);
    EXPECT_EQ(r.object_poses[t].q.coeffs(), b.object_poses[t].q.coeffs());
    // A hand-held object stays within arm's reach of the head.
    EXPECT_LT(r.object_poses[t].t.norm(), 1.5) << "frame " << t;
  }
  ASSERT_TRUE(r.object_mesh);
  EXPECT_EQ(r.object_mesh->vertices, b.object_mesh->vertices);
  EXPECT_EQ(r.object_mesh->faces, b.object_mesh->faces);

  // The model handed in as the GLB itself (the form SAM 3D writes) reads
  // through assimp.
  std::filesystem::remove(dir.path() / "object" / "mesh.obj");
  std::filesystem::copy_file(glb, dir.path() / "object" / "mesh.glb");
  const ClipBundle g = ReadBundle(dir.path());
  ASSERT_TRUE(g.object_mesh);
  EXPECT_EQ(g.object_mesh->vertices, raw.vertices);

  // The same model in millimetres is caught as a units error naming the file.
  std::filesystem::remove(dir.path() / "object" / "mesh.glb");
  TriMesh mm = raw;
  mm.vertices *= 1000.0;
  SaveObj(mm, dir.path() / "object" / "mesh.obj");
  try {
    ReadBundle(dir.path());
    ADD_FAILURE() << "millimetre mesh accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_bundle");
    EXPECT_NE(e.site().file.find("object/mesh.obj"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("millimetres"), std::string::npos) << e.what();
  }

  // The model compared with itself gives a perfect score; against its
  // millimetre twin it does not.
  ReconMetricsConfig cfg;
  cfg.samples = 3000;
  EXPECT_EQ(CompareSurfaces(raw, *r.object_mesh, cfg).f_5mm, 1.0);
  EXPECT_LT(CompareSurfaces(mm, raw, cfg).f_10mm, 0.01);
}

// ---- UmeTrack hands and the recording as a reconstruction -----------------

double Length(const Joints21& j, int a, int b) { return (j.row(a) - j.row(b)).norm(); }

TEST_F(Hot3dBundleTest, UmeTrackLandmarksFollowTheSkeleton) {
  const Hot3dRecording rec = ReadHot3dRecording(Recording());
  ASSERT_EQ(rec.hands.size(), 2u);
  for (const auto& [side, poses] : rec.hands) {
    ASSERT_EQ(poses.size(), 68u) << side;
    std::vector<Joints21> joints;
    for (const auto& [stamp, p] : poses) {
      const HandSide s = side == "right" ? HandSide::kRight : HandSide::kLeft;
      const auto landmarks = UmeTrackLandmarks(rec.hand_model, p.angles, p.wrist, s);
      // The wrist landmark sits at the rest origin: the wrist transform's translation.
      EXPECT_LT((landmarks[5] - p.wrist.t).norm(), 1e-9) << side;
      joints.push_back(UmeTrackOpenPose21(rec.hand_model, p.angles, p.wrist, s));
    }
    // Rotations about the joints keep every bone's length, frame to frame;
    // a wrong order of the chain or a mm/m slip would not.
    for (int finger = 0; finger < 5; ++finger) {
      for (int k = 1; k < 4; ++k) {
        const int a = 1 + 4 * finger + k - 1, b = a + 1;
        const double first = Length(joints[0], a, b);
        EXPECT_GT(first, 0.012) << side << " bone " << a << "-" << b;
        EXPECT_LT(first, 0.07) << side << " bone " << a << "-" << b;
        for (const Joints21& j : joints) EXPECT_NEAR(Length(j, a, b), first, 1e-9);
      }
    }
    // A human hand: wrist to middle fingertip 15-21 cm when stretched;
    // wrist to middle knuckle 7-12 cm.
    EXPECT_GT(Length(joints[0], 0, 9), 0.07);
    EXPECT_LT(Length(joints[0], 0, 9), 0.12);
    EXPECT_FALSE(JointsLookLikeMillimetres(joints[0]));
  }
}

// Thumb-side normal of the palm: (index knuckle - wrist) x (pinky knuckle -
// wrist), projected on the thumb's direction. Its sign is the hand's
// chirality, which a mirror flips.
double Chirality(const Joints21& j) {
  const Vec3 w = j.row(0).transpose();
  const Vec3 n = (Vec3(j.row(5).transpose()) - w).cross(Vec3(j.row(17).transpose()) - w);
  return n.dot(Vec3(j.row(2).transpose()) - w);
}

TEST_F(Hot3dBundleTest, RecordingBecomesAReconstruction) {
  const Hot3dRecording rec = ReadHot3dRecording(Recording());
  const auto library = Sample() / "object_library";

  // HOT3D's world is z up: the objects that rest, posed with their models,
  // have their lowest points at one table height.
  std::vector<double> bottoms;
  for (const auto& [uid, poses] : rec.objects) {
    const auto glb = library / (uid + ".glb");
    if (std::filesystem::exists(glb)) bottoms.push_back(LoadMesh(glb).Transformed(poses.begin()->second).Min().z());
  }
  ASSERT_EQ(bottoms.size(), 4u);
  const auto [lo, hi] = std::minmax_element(bottoms.begin(), bottoms.end());
  std::printf("resting objects' lowest points: %.4f .. %.4f m\n", *lo, *hi);
  EXPECT_LT(*hi - *lo, 0.02);

  Hot3dReferenceOptions o;
  o.hand = "left";
  const Hot3dReference left = Hot3dToReconstruction(rec, library, o);
  const Reconstruction& r = left.reconstruction;
  EXPECT_EQ(r.frames(), 68);
  EXPECT_NEAR(r.fps, 1e9 * 67 / double(rec.hands.at("left").rbegin()->first - rec.hands.at("left").begin()->first), 1e-9);
  EXPECT_EQ(left.object_uid, "37787722328019") << "the keyboard: the nearest object with a model";
  // The object starts over the origin, its lowest point on the floor.
  const TriMesh posed = left.mesh.Transformed(r.object_poses[0]);
  EXPECT_NEAR(posed.Min().z(), 0.0, 1e-9);
  EXPECT_NEAR(r.object_poses[0].t.head<2>().norm(), 0.0, 1e-9);
  // The hand is above the table.
  for (const Joints21& j : r.right_joints) EXPECT_GT(j.col(2).minCoeff(), -0.005);

  // The coffee pot is the object the left hand holds (a hand's width from
  // its origin); with a 5-cm sphere standing in for its missing model the
  // fingertips touch the surface.
  o.object_uid = "228358276546933";
  EXPECT_THROW(Hot3dToReconstruction(rec, library, o), Error) << "no model, no stand-in";
  o.stand_in = synth::MakeSphere(0.05);
  const Hot3dReference pot = Hot3dToReconstruction(rec, library, o);
  EXPECT_TRUE(pot.stand_in);
  EXPECT_EQ(pot.reconstruction.info["object_model"], "stand-in");
  std::printf("left fingertips to the pot's stand-in: %.4f m; to the keyboard: %.4f m\n",
              pot.mean_fingertip_distance, left.mean_fingertip_distance);
  EXPECT_LT(pot.mean_fingertip_distance, 0.02);
  EXPECT_GT(left.mean_fingertip_distance, 0.05);

  // Mirroring turns the left hand into a right hand.
  o.mirror = true;
  const Hot3dReference mirrored = Hot3dToReconstruction(rec, library, o);
  Hot3dReferenceOptions ro;
  ro.hand = "right";
  const Hot3dReference right = Hot3dToReconstruction(rec, library, ro);
  for (int t = 0; t < 68; t += 17) {
    EXPECT_LT(Chirality(pot.reconstruction.right_joints[t]) * Chirality(right.reconstruction.right_joints[t]), 0);
    EXPECT_GT(Chirality(mirrored.reconstruction.right_joints[t]) * Chirality(right.reconstruction.right_joints[t]), 0);
    EXPECT_NEAR(mirrored.reconstruction.right_joints[t](8, 1), -pot.reconstruction.right_joints[t](8, 1), 1e-12);
  }
  EXPECT_NEAR(mirrored.mesh.Volume(), pot.mesh.Volume(), 1e-12) << "faces stay outward";
  EXPECT_GT(mirrored.mesh.Volume(), 0);
}

// Both hands as one reference: the right hand in right_joints, the left in
// left_joints, each the same joints a one-hand reference of it holds; right
// and left of opposite chirality; mirrored, the slots swap, and each hand is
// the other's reflection.
TEST_F(Hot3dBundleTest, BothHandsBecomeOneTwoHandReference) {
  const Hot3dRecording rec = ReadHot3dRecording(Recording());
  const auto library = Sample() / "object_library";
  Hot3dReferenceOptions o;
  o.hand = "left";
  o.object_uid = "228358276546933";
  o.stand_in = synth::MakeSphere(0.05);
  const Reconstruction left_only = Hot3dToReconstruction(rec, library, o).reconstruction;
  o.both_hands = true;
  const Hot3dReference both = Hot3dToReconstruction(rec, library, o);
  const Reconstruction& r = both.reconstruction;
  ASSERT_EQ(r.frames(), 68);
  ASSERT_EQ(r.left_valid.size(), 68u);
  int right_seen = 0;
  for (int t = 0; t < 68; ++t) {
    EXPECT_TRUE(r.left_valid[t]);
    EXPECT_EQ(r.left_joints[t], left_only.right_joints[t]) << "frame " << t;
    if (!r.right_valid[t]) continue;
    ++right_seen;
    EXPECT_LT(Chirality(r.left_joints[t]) * Chirality(r.right_joints[t]), 0) << "frame " << t;
    // Two hands of one person: their wrists 10 to 80 cm apart.
    const double apart = (r.left_joints[t].row(0) - r.right_joints[t].row(0)).norm();
    EXPECT_GT(apart, 0.1);
    EXPECT_LT(apart, 0.8);
  }
  std::printf("both hands: right hand seen in %d of 68 frames\n", right_seen);
  EXPECT_GT(right_seen, 60);
  EXPECT_EQ(r.info["both_hands"], true);

  o.mirror = true;
  const Reconstruction m = Hot3dToReconstruction(rec, library, o).reconstruction;
  for (int t = 0; t < 68; t += 11) {
    EXPECT_EQ(m.right_valid[t], r.left_valid[t]);
    EXPECT_NEAR(m.right_joints[t](8, 1), -r.left_joints[t](8, 1), 1e-12);
    EXPECT_NEAR(m.left_joints[t](8, 0), r.right_joints[t](8, 0), 1e-12);
  }
}

TEST_F(Hot3dBundleTest, MalformedRowsAreNamed) {
  TempDir dir;
  for (const char* f : {"dynamic_objects.csv", "umetrack_hand_pose_trajectory.jsonl", "umetrack_hand_user_profile.json"}) {
    std::filesystem::copy_file(Recording() / f, dir.path() / f);
  }
  auto expect = [&](const std::string& file, long line, const std::string& field) {
    try {
      ReadHot3dRecording(dir.path());
      ADD_FAILURE() << "accepted a bad " << file;
    } catch (const Error& e) {
      EXPECT_NE(e.site().file.find(file), std::string::npos) << e.what();
      EXPECT_EQ(e.site().line, line) << e.what();
      EXPECT_EQ(e.site().field, field) << e.what();
    }
  };
  // A NaN translation in row 3 of the object table.
  const auto csv = dir.path() / "dynamic_objects.csv";
  std::string text = ReadFile(csv);
  const size_t row3 = text.find('\n', text.find('\n', text.find('\n') + 1) + 1) + 1;
  const size_t cell = text.find(',', text.find(',', row3) + 1) + 1;
  text.replace(cell, text.find(',', cell) - cell, "nan");
  WriteFile(csv, text);
  expect("dynamic_objects.csv", 4, "t_wo_x[m]");
  std::filesystem::copy_file(Recording() / "dynamic_objects.csv", csv, std::filesystem::copy_options::overwrite_existing);
  // 21 joint angles on line 2 of the hand poses.
  const auto jsonl = dir.path() / "umetrack_hand_pose_trajectory.jsonl";
  text = ReadFile(jsonl);
  const size_t line2 = text.find('\n') + 1;
  const size_t angles = text.find("\"joint_angles\": [", line2) + 17;
  text.erase(angles, text.find(',', angles) + 1 - angles);
  WriteFile(jsonl, text);
  expect("umetrack_hand_pose_trajectory.jsonl", 2, "joint_angles");
}

}  // namespace
}  // namespace doasido::recon
