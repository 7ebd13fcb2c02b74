// Geometry of the synthetic world: hand proportions and mirroring, closed
// meshes, and grasps whose fingers end on the object surface (the
// rasteriser's tests: tests/video_mesh_rasterizer_test.cc).
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "synth/episode.h"
#include "synth/hand_model.h"
#include "synth/objects.h"
#include "synth/render.h"
#include "tests/test_util.h"

namespace doasido::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 Row(const HandJoints& j, int i) { return j.row(i).transpose(); }

TEST(HandModel, BoneLengthsMatchShapeForAnyPose) {
  HandShape shape;
  HandPose pose = RelaxedPose(
      Pose{Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized())), Vec3(0.1, -0.2, 0.5)});
  for (int f = 0; f < 5; ++f) SetFingerCurl(pose, f, 0.2 * f);
  pose.abduct = {0.2, -0.1, 0.05, 0.1, 0.2};
  for (Side side : {Side::kLeft, Side::kRight}) {
    const HandJoints j = HandJointPositions(pose, side, shape);
    for (int f = 0; f < 5; ++f) {
      for (int s = 0; s < 3; ++s) {
        const int a = 1 + 4 * f + s;
        EXPECT_NEAR((Row(j, a + 1) - Row(j, a)).norm(), shape.length[f][s], 1e-12)
            << "finger " << f << " segment " << s;
      }
    }
    EXPECT_NEAR((Row(j, 0) - pose.wrist.t).norm(), 0.0, 1e-12);
  }
}

TEST(HandModel, AdultProportionsAndOpenPoseOrder) {
  HandPose flat;  // identity wrist, all angles zero: fingers straight along +y
  const HandJoints j = HandJointPositions(flat, Side::kRight);
  // Wrist to middle fingertip of an adult hand is about 17-20 cm.
  EXPECT_GT(Row(j, 12).y(), 0.17);
  EXPECT_LT(Row(j, 12).y(), 0.20);
  // Middle finger is the longest, pinky the shortest.
  EXPECT_GT(Row(j, 12).y(), Row(j, 8).y());
  EXPECT_GT(Row(j, 12).y(), Row(j, 16).y());
  EXPECT_GT(Row(j, 16).y(), Row(j, 20).y());
  // Radial order along +x on a right hand: thumb, index, middle, ring, pinky.
  EXPECT_GT(Row(j, 4).x(), Row(j, 8).x());
  EXPECT_GT(Row(j, 5).x(), Row(j, 9).x());
  EXPECT_GT(Row(j, 9).x(), Row(j, 13).x());
  EXPECT_GT(Row(j, 13).x(), Row(j, 17).x());
}

TEST(HandModel, LeftIsMirrorOfRight) {
  HandPose pose = RelaxedPose(Pose::Identity());
  for (int f = 0; f < 5; ++f) SetFingerCurl(pose, f, 0.5);
  const HandJoints r = HandJointPositions(pose, Side::kRight);
  const HandJoints l = HandJointPositions(pose, Side::kLeft);
  for (int i = 0; i < 21; ++i) {
    EXPECT_NEAR(l(i, 0), -r(i, 0), 1e-12);
    EXPECT_NEAR(l(i, 1), r(i, 1), 1e-12);
    EXPECT_NEAR(l(i, 2), r(i, 2), 1e-12);
  }
}

TEST(HandModel, FlexionCurlsTowardsThePalm) {
  HandPose pose;
  const HandJoints open = HandJointPositions(pose, Side::kRight);
  for (int f = 0; f < 5; ++f) SetFingerCurl(pose, f, 1.0);
  const HandJoints fist = HandJointPositions(pose, Side::kRight);
  for (int tip : {8, 12, 16, 20}) {
    EXPECT_LT((Row(fist, tip) - Row(fist, 0)).norm(), (Row(open, tip) - Row(open, 0)).norm());
    EXPECT_GT(Row(fist, tip).z(), 0.01);  // palmar side is +z
  }
}

TEST(HandModel, CapsuleMeshIsClosedAndFollowsThePose) {
  HandPose pose = RelaxedPose(Pose{Quat::Identity(), Vec3(0, 0, 0.4)});
  const PosedHand hand = PoseHand(pose, Side::kLeft);
  double expected = 0;
  for (const Capsule& c : hand.capsules) {
    const double r = c.radius, len = (c.b - c.a).norm();
    expected += kPi * r * r * len + 4.0 / 3.0 * kPi * r * r * r;
  }
  // Sum of the capsules' own volumes (they overlap, so compare the sum).
  EXPECT_NEAR(hand.mesh.Volume(), expected, 0.06 * expected);
  // Every edge is shared by exactly two faces: a closed surface.
  std::map<std::pair<int, int>, int> edges;
  for (int f = 0; f < hand.mesh.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = hand.mesh.faces(f, k), b = hand.mesh.faces(f, (k + 1) % 3);
      edges[{a, b}]++;
    }
  }
  for (const auto& [e, n] : edges) {
    ASSERT_EQ(n, 1);
    ASSERT_EQ(edges.count({e.second, e.first}), 1u) << "open edge";
  }
  // The same topology for another pose.
  for (int f = 0; f < 5; ++f) SetFingerCurl(pose, f, 0.9);
  const PosedHand fist = PoseHand(pose, Side::kLeft);
  EXPECT_EQ(fist.mesh.num_vertices(), hand.mesh.num_vertices());
  EXPECT_EQ(fist.mesh.faces, hand.mesh.faces);
}

TEST(Objects, VolumesRestingPlaneAndInsideTest) {
  const TriMesh box = MakeBox(0.1, 0.2, 0.3);
  EXPECT_NEAR(box.Volume(), 0.006, 1e-12);
  const TriMesh cyl = MakeCylinder(0.05, 0.1, 64);
  EXPECT_NEAR(cyl.Volume(), kPi * 0.05 * 0.05 * 0.1, 0.01 * cyl.Volume());
  const TriMesh sph = MakeSphere(0.05, 48, 32);
  EXPECT_NEAR(sph.Volume(), 4.0 / 3.0 * kPi * std::pow(0.05, 3), 0.02 * sph.Volume());
  const TriMesh mug = MakeMug(0.04, 0.1, 0.006, 64);
  const double shell = kPi * 0.04 * 0.04 * 0.1 - kPi * 0.034 * 0.034 * 0.094;
  EXPECT_GT(mug.Volume(), shell);        // wall + handle
  EXPECT_LT(mug.Volume(), 1.5 * shell);  // the cavity is not filled
  for (const TriMesh* m : {&box, &cyl, &sph, &mug}) EXPECT_NEAR(m->Min().z(), 0.0, 1e-12);
  EXPECT_TRUE(InsideMesh(cyl, Vec3(0, 0, 0.05)));
  EXPECT_FALSE(InsideMesh(cyl, Vec3(0.06, 0, 0.05)));
  EXPECT_FALSE(InsideMesh(mug, Vec3(0, 0, 0.05)));     // in the cavity
  EXPECT_TRUE(InsideMesh(mug, Vec3(0.037, 0, 0.05)));  // in the wall
  EXPECT_NEAR(DistanceToMesh(box, Vec3(0, 0, 0.4)), 0.1, 1e-12);
}

TEST(Objects, MeshFileRestsOnTheTable) {
  const TriMesh m =
      LoadObjectMesh(testing::SharedData() / "meshes/ycb/006_mustard_bottle_textured.obj");
  EXPECT_EQ(m.num_faces(), 16384);  // the file header says 16384 faces
  EXPECT_NEAR(m.Min().z(), 0.0, 1e-12);
  EXPECT_NEAR(m.Min().x() + m.Max().x(), 0.0, 1e-12);
  EXPECT_GT(m.Max().z(), 0.15);  // a 19 cm bottle
}

// Finger clearance of `side`'s hand in `frame` against the posed object:
// the least over its fingers' capsules (m; negative inside).
double FingerClearance(const EpisodeFrame& frame, Side side, const TriMesh& object) {
  const TriMesh posed = object.Transformed(frame.object_pose);
  const PosedHand hand = PoseHand(*frame.hands[static_cast<int>(side)], side);
  double clearance = 1e9;
  for (int c = 0; c < 15; ++c) {
    const Capsule& cap = hand.capsules[c];
    for (int k = 0; k <= 8; ++k) {
      const Vec3 p = cap.a + (cap.b - cap.a) * (k / 8.0);
      clearance = std::min(clearance, (InsideMesh(posed, p) ? -1 : 1) * DistanceToMesh(posed, p) - cap.radius);
    }
  }
  return clearance;
}

TEST(Grasp, FingertipsEndOnTheSurface) {
  for (const TriMesh& object : {MakeCylinder(0.035, 0.12), MakeBox(0.06, 0.06, 0.1)}) {
    const Grasp g = SolveGrasp(object, Side::kRight, -0.3, 0.5, 0.2);
    const Pose rest{Quat(Eigen::AngleAxisd(0.2, Vec3::UnitZ())), Vec3::Zero()};
    const TriMesh posed = object.Transformed(rest);
    HandPose pose = RelaxedPose(rest * g.wrist_in_object);
    for (int f = 0; f < 5; ++f) SetFingerCurl(pose, f, g.curl[f]);
    const PosedHand hand = PoseHand(pose, Side::kRight);
    int touching = 0;
    for (int f = 0; f < 5; ++f) {
      if (!g.touching[f]) continue;
      ++touching;
      double clearance = 1e9;
      for (int s = 0; s < 3; ++s) {
        const Capsule& c = hand.capsules[3 * f + s];
        for (int k = 0; k <= 8; ++k) {
          const Vec3 p = c.a + (c.b - c.a) * (k / 8.0);
          clearance = std::min(clearance, DistanceToMesh(posed, p) - c.radius);
          EXPECT_FALSE(InsideMesh(posed, p)) << "finger " << f << " inside the object";
        }
      }
      EXPECT_LT(std::abs(clearance), 0.0015) << "finger " << f;
    }
    EXPECT_GE(touching, 4);
  }
}

// Where finger f's distal segment comes closest to the object's vertical
// axis: the horizontal angle (radians, object frame) of that point.
double ContactAngle(const PosedHand& hand, int f, const Pose& object) {
  const Capsule& c = hand.capsules[3 * f + 2];
  double best = 1e9, angle = 0;
  for (int k = 0; k <= 16; ++k) {
    const Vec3 p = object.Inverse() * Vec3(c.a + (c.b - c.a) * (k / 16.0));
    if (p.head<2>().norm() < best) best = p.head<2>().norm(), angle = std::atan2(p.y(), p.x());
  }
  return angle;
}

// A pinch puts the thumb and the index and middle fingers on opposite sides
// of the object, each on its surface, for either hand, round and flat
// objects and any yaw; and through a whole pick-and-place the hand's flags
// stay exact (on the surface when flagged, never inside).
TEST(Grasp, APinchOpposesTheThumbToTheFingers) {
  const std::vector<TriMesh> objects = {MakeCylinder(0.03, 0.09, 16), MakeCylinder(0.04, 0.09, 16),
                                        MakeBox(0.05, 0.05, 0.08), MakeBox(0.06, 0.06, 0.09)};
  double least_opposition = kPi;
  for (size_t o = 0; o < objects.size(); ++o) {
    for (const Side side : {Side::kRight, Side::kLeft}) {
      for (const double yaw : {0.0, 0.4, 0.8}) {
        const Grasp g = SolvePinchGrasp(objects[o], side, -0.35, 0.55, yaw);
        const Pose rest{Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ())), Vec3::Zero()};
        HandPose pose = RelaxedPose(rest * g.wrist_in_object);
        for (int f = 0; f < 5; ++f) SetFingerCurl(pose, f, g.curl[f]);
        EpisodeFrame frame;
        frame.object_pose = rest;
        frame.hands[static_cast<int>(side)] = pose;
        EXPECT_LT(std::abs(FingerClearance(frame, side, objects[o])), 0.0015) << "object " << o;
        const PosedHand hand = PoseHand(pose, side);
        for (int f = 0; f < 3; ++f) {
          ASSERT_TRUE(g.touching[f]) << "object " << o << " yaw " << yaw << " finger " << f;
        }
        const double thumb = ContactAngle(hand, 0, rest);
        for (int f = 1; f < 3; ++f) {
          const double gap = std::abs(std::remainder(ContactAngle(hand, f, rest) - thumb, 2 * kPi));
          least_opposition = std::min(least_opposition, gap);
        }
      }
    }
  }
  std::printf("pinch: thumb and finger contacts at least %.0f degrees apart round the object\n",
              least_opposition * 180 / kPi);
  // Two contacts hold by friction alone when the line between them lies in
  // both friction cones: with the simulation's friction 1 (45-degree cones)
  // that needs them over 90 degrees apart round a round object.
  EXPECT_GT(least_opposition, 100 * kPi / 180);
  for (const Verb verb : {Verb::kPickPlace, Verb::kLiftRotate}) {
    EpisodeSpec spec;
    spec.verb = verb;
    spec.grasp = GraspType::kPinch;
    spec.frames = 60;
    const Episode ep = ScriptEpisode(spec, objects[0]);
    int held = 0;
    for (size_t t = 0; t < ep.frames.size(); ++t) {
      const double clearance = FingerClearance(ep.frames[t], Side::kRight, objects[0]);
      if (ep.frames[t].contact[1]) {
        ++held;
        EXPECT_LT(std::abs(clearance), 0.0015) << VerbName(verb) << " frame " << t;
      } else {
        EXPECT_GT(clearance, -0.0015) << VerbName(verb) << " frame " << t << " finger inside";
      }
    }
    EXPECT_GT(held, 20) << VerbName(verb);
  }
  EXPECT_EQ(GraspTypeFromName(GraspTypeName(GraspType::kPinch)), GraspType::kPinch);
  EXPECT_EQ(doasido::testing::ErrorCode([] { GraspTypeFromName("fist"); }), "bad_config");
}

// The two-hand tasks' ground truth: a hand flagged in contact has its
// fingers on the object's surface; the object moves only while a hand
// holds it (both hands, when it is carried together; holding in the frame
// before or after the step); a hand that holds nothing is not inside it.
TEST(TwoHands, ContactFlagsAreExactForEveryTask) {
  const TriMesh object = MakeCylinder(0.035, 0.12);
  for (const GraspType grasp : {GraspType::kWrap, GraspType::kPinch}) {
    for (const TwoHandTask task : {TwoHandTask::kHandover, TwoHandTask::kCarry, TwoHandTask::kHoldAndAct}) {
      SCOPED_TRACE(GraspTypeName(grasp));
      EpisodeSpec spec;
      spec.frames = 60;
      spec.two_hand_task = task;
      spec.grasp = grasp;
      const Episode ep = ScriptEpisode(spec, object);
      ASSERT_EQ(ep.frames.size(), 60u);
      int moved = 0, both = 0;
      for (size_t t = 0; t < ep.frames.size(); ++t) {
        const EpisodeFrame& f = ep.frames[t];
        ASSERT_TRUE(f.hands[0] && f.hands[1]) << TwoHandTaskName(task);
        for (const Side side : {Side::kLeft, Side::kRight}) {
          const double clearance = FingerClearance(f, side, object);
          if (f.contact[static_cast<int>(side)]) {
            EXPECT_LT(std::abs(clearance), 0.0015) << TwoHandTaskName(task) << " frame " << t;
          } else {
            EXPECT_GT(clearance, -0.0015) << TwoHandTaskName(task) << " frame " << t << " finger inside";
          }
        }
        both += f.contact[0] && f.contact[1];
        if (t == 0) continue;
        const EpisodeFrame& prev = ep.frames[t - 1];
        const bool moves = (f.object_pose.t - prev.object_pose.t).norm() > 1e-9 ||
                           f.object_pose.q.angularDistance(prev.object_pose.q) > 1e-9;
        if (!moves) continue;
        ++moved;
        // Moving from frame t-1 to t: held in one of the two.
        const bool left = prev.contact[0] || f.contact[0], right = prev.contact[1] || f.contact[1];
        EXPECT_TRUE(left || right) << TwoHandTaskName(task) << " moves free in frame " << t;
        if (task == TwoHandTask::kCarry) {
          EXPECT_TRUE(left && right) << "frame " << t;
        }
      }
      std::printf("%s: object moves in %d frames, both hands hold it in %d\n", TwoHandTaskName(task), moved, both);
      EXPECT_GT(both, 0) << TwoHandTaskName(task);
      if (task == TwoHandTask::kHoldAndAct) {
        EXPECT_EQ(moved, 0);
      } else {
        EXPECT_GT(moved, 10);
      }
    }
  }
}

}  // namespace
}  // namespace doasido::synth
