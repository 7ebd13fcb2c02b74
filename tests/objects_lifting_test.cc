// Lifting box keypoints to a box up to scale (objects/box_lifting.h), the
// metric scale from touching fingertips (objects/object_scale.h) and the
// object's mesh (objects/object_shape.h), against boxes whose keypoints are
// exact projections of a known box (random poses, a known K, known extents).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "objects/box_lifting.h"
#include "objects/object_detection.h"
#include "objects/object_categories.h"
#include "objects/object_scale.h"
#include "objects/object_shape.h"

namespace doasido::objects {
namespace {

Mat3 TestK() {
  Mat3 K;
  K << 900, 0, 639.5, 0, 905, 359.5, 0, 0, 1;
  return K;
}

struct TrueBox {
  Pose pose;
  Vec3 size;
};

// A box 5-30 cm a side, 0.4-1.5 m in front of the camera, turned anyhow,
// inside a 1280 x 720 view.
TrueBox RandomBox(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1), side(0.05, 0.30), depth(0.4, 1.5);
  TrueBox b;
  b.pose.q = Quat(u(rng), u(rng), u(rng), u(rng)).normalized();
  const double z = depth(rng);
  b.pose.t = Vec3(0.25 * z * u(rng), 0.15 * z * u(rng), z);
  b.size = Vec3(side(rng), side(rng), side(rng));
  return b;
}

TEST(BoxLifting, RecoversRotationCentreAndProportionsExactlyFromExactKeypoints) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 200; ++i) {
    const TrueBox b = RandomBox(rng);
    const LiftedBox l = LiftBox(ProjectBox(b.pose, b.size, TestK()), TestK(), 0.0);
    const double g = CharacteristicSize(b.size);
    EXPECT_LT(RotationAngle(Quat(l.R), b.pose.q), 1e-6) << i;
    EXPECT_LT((l.t - b.pose.t / g).norm(), 1e-6 * b.pose.t.norm() / g) << i;
    EXPECT_LT((l.size - b.size / g).norm(), 1e-6) << i;
    EXPECT_LT(l.rms_px, 1e-6) << i;
  }
}

// With 1 px of keypoint noise (sigma per axis) the errors are stated as
// bounds on the 90th percentile over 200 boxes.
TEST(BoxLifting, OnePixelOfNoiseKeepsRotationWithinDegreesAndProportionsWithinPercent) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0, 1.0);
  std::vector<double> turn, shape, direction;
  for (int i = 0; i < 200; ++i) {
    const TrueBox b = RandomBox(rng);
    BoxKeypoints k = ProjectBox(b.pose, b.size, TestK());
    for (Vec2& p : k) p += Vec2(noise(rng), noise(rng));
    const LiftedBox l = LiftBox(k, TestK(), 0.0);
    const double g = CharacteristicSize(b.size);
    turn.push_back(RotationAngle(Quat(l.R), b.pose.q) * 180 / M_PI);
    shape.push_back((l.size.array() / (b.size / g).array() - 1).abs().maxCoeff());
    direction.push_back(std::acos(std::min(1.0, l.t.normalized().dot(b.pose.t.normalized()))) * 180 / M_PI);
  }
  auto p90 = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() * 9 / 10];
  };
  EXPECT_LT(p90(turn), 3.0);       // degrees
  EXPECT_LT(p90(shape), 0.10);     // relative, per extent
  EXPECT_LT(p90(direction), 0.2);  // degrees: the centre's ray
}

TEST(BoxLifting, FlagsAThinSlabAsDegenerate) {
  const Pose pose{Quat(Eigen::AngleAxisd(0.4, Vec3(1, 1, 0).normalized())), Vec3(0.05, 0, 0.8)};
  const LiftedBox slab = LiftBox(ProjectBox(pose, Vec3(0.2, 0.15, 0.01), TestK()), TestK(), 0.2);
  EXPECT_TRUE(slab.degenerate);
  const LiftedBox cube = LiftBox(ProjectBox(pose, Vec3(0.1, 0.12, 0.09), TestK()), TestK(), 0.2);
  EXPECT_FALSE(cube.degenerate);
}

TEST(BoxLifting, SideViewPutsAnUprightCylinderAtItsDepth) {
  // An upright 12 cm cup straight ahead, axis square to the view.
  const Pose pose{Quat(Eigen::AngleAxisd(M_PI, Vec3::UnitX())), Vec3(0.02, 0.01, 0.6)};
  const Vec3 size(0.09, 0.12, 0.09);
  const BoxKeypoints k = ProjectBox(pose, size, TestK());
  const Pose side = SideViewPose(k, TestK(), size.y());
  // The image's face centres are averages of projected corners, not the
  // projections of the faces' centres: 1.1 % of the depth and 1 degree of
  // the axis here (measured 6.7 mm, 0.95 degrees).
  EXPECT_NEAR(side.t.z(), 0.6, 0.012);
  EXPECT_LT((side.t - pose.t).norm(), 0.012);
  EXPECT_LT(std::acos(std::abs(side.R().col(1).dot(pose.R().col(1)))), 2 * M_PI / 180);
}

TEST(BoxLifting, CanonicalYawKeepsTheAxisAndForgetsTheTurnAboutIt) {
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(0.2, 1, 0.3).normalized()).toRotationMatrix();
  const Mat3 turned = R * Eigen::AngleAxisd(1.1, Vec3::UnitY()).toRotationMatrix();
  EXPECT_LT((CanonicalYaw(R) - CanonicalYaw(turned)).norm(), 1e-12);
  EXPECT_LT((CanonicalYaw(R).col(1) - R.col(1)).norm(), 1e-12);
  EXPECT_NEAR(CanonicalYaw(R).determinant(), 1, 1e-12);
}

// Fingertips on the surface of a known box over 10 frames, the poses up to
// scale from the exact lift: the scale is the box's own.
void ExpectContactScale(bool cylinder, double offset) {
  std::mt19937_64 rng(cylinder ? 3 : 5);
  std::uniform_real_distribution<double> u(-1, 1);
  const Vec3 size = cylinder ? Vec3(0.08, 0.11, 0.08) : Vec3(0.07, 0.16, 0.11);
  const double g = CharacteristicSize(size);
  std::vector<UnitPose> poses;
  std::vector<FingertipContact> contacts;
  for (int f = 0; f < 10; ++f) {
    TrueBox b = RandomBox(rng);
    b.size = size;
    const LiftedBox l = LiftBox(ProjectBox(b.pose, b.size, TestK()), TestK(), 0.0);
    poses.push_back({l.R, l.t});
    for (int k = 0; k < 3; ++k) {
      // A point on the surface, moved `offset` out along its normal.
      Vec3 q;
      Vec3 normal;
      if (cylinder) {
        const double a = M_PI * u(rng);
        normal = Vec3(std::sin(a), 0, std::cos(a));
        q = normal * size.x() / 2 + Vec3(0, u(rng) * size.y() / 2 * 0.9, 0);
      } else {
        const int axis = k;
        normal = Vec3::Zero();
        normal[axis] = u(rng) < 0 ? -1 : 1;
        q = Vec3(u(rng), u(rng), u(rng)).cwiseProduct(size) / 2 * 0.9;
        q[axis] = normal[axis] * size[axis] / 2;
      }
      contacts.push_back({f, b.pose * Vec3(q + offset * normal)});
    }
  }
  const Vec3 shape = size / g;
  const ContactScale fit = FitContactScale(poses, shape, cylinder, contacts, 0.1,
                                           {.fingertip_offset_m = offset});
  EXPECT_NEAR(fit.scale, g, 1e-6 * g);
  EXPECT_LT(fit.residual_median_m, 1e-7);
}

TEST(ContactScale, FingertipsOnABoxGiveItsSize) { ExpectContactScale(false, 0.0); }
TEST(ContactScale, FingertipsOnACylinderGiveItsSize) { ExpectContactScale(true, 0.0); }
TEST(ContactScale, TheFingertipOffsetIsTakenOff) { ExpectContactScale(true, 0.008); }

TEST(ContactScale, SurfaceDistanceOfABoxAndACylinder) {
  const Vec3 size(0.2, 0.4, 0.6);
  EXPECT_NEAR(SurfaceDistance(Vec3(0.15, 0, 0), size, false), 0.05, 1e-15);
  EXPECT_NEAR(SurfaceDistance(Vec3(0, 0, 0), size, false), -0.1, 1e-15);
  EXPECT_NEAR(SurfaceDistance(Vec3(0.13, 0.24, 0), size, false), 0.05, 1e-15);
  EXPECT_NEAR(SurfaceDistance(Vec3(0.06, 0, 0.08), size, true), 0.0, 1e-15);  // r = 0.1
  EXPECT_NEAR(SurfaceDistance(Vec3(0, 0.25, 0), size, true), 0.05, 1e-15);
}

double SignedVolume(const TriMesh& m) {
  double v = 0;
  for (int f = 0; f < m.faces.rows(); ++f) {
    const Vec3 a = m.vertices.row(m.faces(f, 0)), b = m.vertices.row(m.faces(f, 1)),
               c = m.vertices.row(m.faces(f, 2));
    v += a.dot(b.cross(c)) / 6;
  }
  return v;
}

TEST(ObjectShape, ClosedOutwardMeshesOfTheBoxsExtents) {
  const Vec3 size(0.08, 0.11, 0.06);
  const TriMesh box = ObjectMesh(size, false);
  EXPECT_NEAR(SignedVolume(box), size.prod(), 1e-15);
  EXPECT_LT((box.vertices.colwise().maxCoeff().transpose() - size / 2).norm(), 1e-15);
  const int n = 256;
  const TriMesh cylinder = ObjectMesh(size, true, n);
  // The inscribed polygon's area times the height.
  const double r = size.x() / 2;
  EXPECT_NEAR(SignedVolume(cylinder), 0.5 * n * r * r * std::sin(2 * M_PI / n) * size.y(), 1e-12);
  EXPECT_NEAR(cylinder.vertices.col(1).maxCoeff(), size.y() / 2, 1e-15);
}

// The hands stage's metric joints as the tracker's 2D hands: projected by
// K (pixel centres at integers) into pixel-corner coordinates, under the
// file frame first_frame + t; invalid frames and hands behind the camera
// left out.
TEST(HandsFromBundle, ProjectsTheJointsByKUnderFileFrames) {
  recon::ClipBundle b;
  b.frames = 3;
  Mat3 K;
  K << 500, 0, 319.5, 0, 500, 239.5, 0, 0, 1;
  b.K = {K};
  recon::HandTrack h;
  h.valid = {true, false, true};
  for (int t = 0; t < 3; ++t) {
    recon::Joints21 j;
    for (int k = 0; k < 21; ++k) j.row(k) = Eigen::RowVector3d(0.01 * k, -0.02 + 0.001 * t, 0.5);
    if (t == 2) j(5, 2) = -0.1;  // one joint behind the camera
    h.joints.push_back(j);
  }
  b.hand_right = h;
  const HandsByFrame hands = HandsFromBundle(b, 100);
  ASSERT_EQ(hands.size(), 1u);
  ASSERT_EQ(hands.count(100), 1u);
  const HandPoints2d& p = hands.at(100).at(0);
  for (int k = 0; k < 21; ++k) {
    EXPECT_NEAR(p[k].x(), 500 * 0.01 * k / 0.5 + 319.5 + 0.5, 1e-9);
    EXPECT_NEAR(p[k].y(), 500 * -0.02 / 0.5 + 239.5 + 0.5, 1e-9);
  }
}

}  // namespace
}  // namespace doasido::objects
